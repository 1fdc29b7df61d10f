"""Sweeps (experiments): studies over scenarios, strategies, faults and seeds, run on a
local process pool or a Dask cluster, and compared with the statistics a paper needs
(``docs/sweeps.md``). The command line is in ``sweeps/cli.py``; everything else imports
pandas, pyarrow and matplotlib (the optional ``sweep`` extra)."""
