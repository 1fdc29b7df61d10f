"""Procedural maps (issue 34, part 1): seeded buildings, offices, caves and rubble sites."""
