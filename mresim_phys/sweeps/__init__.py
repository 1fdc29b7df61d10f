"""Sweeps (experiments): studies over scenarios, strategies, faults and seeds, run on a
local process pool or a Dask cluster, and compared with the statistics a paper needs
(``docs/sweeps.md``). The command line is in ``sweeps/cli.py``; everything else imports
pandas, pyarrow and matplotlib (the optional ``sweep`` extra)."""


def __getattr__(name: str) -> object:
    """``run_study`` (``sweeps/api.py``), imported with pandas when first asked for."""
    if name == "run_study":
        from mresim_phys.sweeps.api import run_study

        return run_study
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
