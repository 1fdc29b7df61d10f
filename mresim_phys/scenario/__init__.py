"""Input (phase 0): a scenario file -> a validated, picklable ``Scenario``.

``schema`` (the pydantic models of the YAML contract), ``load`` (read, validate,
resolve paths, readable errors), ``overrides`` (deep-merge rules for overrides and
sweeps) and ``readers`` (map files and YAML).
"""
