"""mpmflow: incompressible free-surface flow with the material point method and Chorin's
projection (Kularathna & Soga 2017). SI units throughout.

    import mpmflow
    case = mpmflow.load_case("examples/dam_break.toml", {"grid.spacing": 0.008})
    summary = mpmflow.Simulation(case, out_dir="runs/db8").run()
    run = mpmflow.open_run("runs/db8")
    run.timeseries["front"], run.snapshots[-1].read()["pressure"]

The README's "Python API" section says more.
"""

from typing import TYPE_CHECKING, Any

from ._version import __version__

if TYPE_CHECKING:  # what __getattr__ returns by name, for type checkers
    from .case import load_case, validate_case
    from .errors import CaseError, SimulationError
    from .results import open_run
    from .simulation import IterationInterval, Simulation, TimeInterval, WallTimeInterval

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


def _import_on_first_use(name: str) -> Any:  # Any: a different object by name
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


# the module's __getattr__ (PEP 562). Bound by assignment, not `def __getattr__`: mypy
# answers `from .. import _core` in state/ (the compiled core, without type information)
# with a module __getattr__'s return type, which a typed def in mpmflow's import cycle
# leaves unresolved ("Any? has no attribute ...", mypy 1.x); a bound name reads as Any
__getattr__ = _import_on_first_use
