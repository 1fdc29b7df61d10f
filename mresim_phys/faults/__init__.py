"""Fault models (phase 0, events; and the end of each step, for batteries).

``spec`` holds the scenario's ``faults:`` block (random failures, a battery, hazard
zones, the out-of-contact rule) as validated models; ``clocks`` draws every robot's
failure clocks from named streams of the seed; ``runtime`` applies them to a run.
"""
