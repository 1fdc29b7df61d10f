"""Ground classes and what each robot can cross (issue 33, part 3): spec, grid and feature."""
