"""Robots with their own clocks (issue 33, part 2): the ``clock:`` block, state and gates."""
