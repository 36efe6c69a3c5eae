"""The operator UI in the browser: ``cnc ui web`` (server.py) and its page (static/)."""
