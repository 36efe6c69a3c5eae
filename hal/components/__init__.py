"""Realtime components, one module each, loaded into the host with ``loadrt NAME``."""
