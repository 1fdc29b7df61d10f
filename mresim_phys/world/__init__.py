"""The true world (phases 0-2): geometry, its changes, sensing and scheduled events.

``maps`` (grid -> exact wall segments, reachable free space), ``space`` (the ``World``:
truth grid and pymunk Space together), ``changes`` / ``wallset`` / ``reach`` (what a
change did, the segments replaced around it, the reachable set followed), ``sensing``
(laser scans) and ``events`` (the event plugin family).
"""
