"""NML: typed messages through shared-memory buffers guarded by semaphores (SPEC NML-*)."""
