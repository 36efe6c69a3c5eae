"""The text user interfaces: ``cnc top`` (live status view) and ``cnc sh`` (command shell).

Both are clients of the public API (``cnc.stat``, ``cnc.command``, ``cnc.error_channel``),
like any third-party UI:

- ``top``: the full-screen view (curses) and its ``--once`` plain-text snapshot;
- ``sh``: the shell, its command table, script files and ``-c``;
- ``controller``: the API objects of one controller, made again after it restarts, and the
  operator messages read from its error channel;
- ``formatting``: status values as text (state names, positions, G/M codes) and number input.
"""
