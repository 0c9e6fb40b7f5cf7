"""mpmflow: incompressible free-surface flow with the material point method and Chorin's
projection (Kularathna & Soga 2017). SI units throughout.

    import mpmflow
    case = mpmflow.load_case("examples/dam_break.toml", {"grid.spacing": 0.008})
    summary = mpmflow.Simulation(case, out_dir="runs/db8").run()
    run = mpmflow.open_run("runs/db8")
    run.timeseries["front"], run.snapshots[-1].read()["pressure"]

The README's "Python API" section says more.
"""

from ._version import __version__

__all__ = [
    "load_case",
    "validate_case",
    "Simulation",
    "open_run",
    "CaseError",
    "SimulationError",
    "TimeInterval",
    "IterationInterval",
    "WallTimeInterval",
    "__version__",
]


def __getattr__(name):
    # imported on first use, so that `mpmflow --help` and `mpmflow keys` start quickly
    if name == "load_case":
        from .case import load_case

        return load_case
    if name == "validate_case":
        from .case import validate_case

        return validate_case
    if name in ("Simulation", "TimeInterval", "IterationInterval", "WallTimeInterval"):
        from . import simulation

        return getattr(simulation, name)
    if name == "open_run":
        from .results import open_run

        return open_run
    if name in ("CaseError", "SimulationError"):
        from . import errors

        return getattr(errors, name)
    raise AttributeError(f"module 'mpmflow' has no attribute {name!r}")
