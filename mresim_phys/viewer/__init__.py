"""Viewer (output edge): explore a run in the browser, live or from its run log.

``mresim view RUN_DIR`` and ``mresim run SCENARIO --view`` (docs/viewer.md). Modules:
``frames`` (snapshots drawn by the video's renderer, as PNG), ``timeline`` (chart series
and event marks), ``replaysource`` (any logged step, through in-memory keyframes),
``livesource`` (a running simulation paused, stepped and stopped from the page),
``protocol`` (the WebSocket messages, bounded), ``guard`` (who may connect: the client's
address, ``Host``, ``Origin``), ``server`` (aiohttp, this machine only by default),
``command`` (the command-line glue) and ``static/`` (the page: plain HTML, JS
and CSS served by the package).
"""
