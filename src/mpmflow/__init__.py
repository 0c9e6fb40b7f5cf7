"""mpmflow: incompressible free-surface flow with the material point method and Chorin's
projection (Kularathna & Soga 2017). SI units throughout.

    from mpmflow import load_case, Simulation
    summary = Simulation(load_case("examples/dam_break.toml"), out_dir="run").run()
"""

from ._version import __version__

__all__ = ["load_case", "Simulation", "__version__"]


def __getattr__(name):
    # imported on first use, so that `mpmflow --help` and `mpmflow keys` start quickly
    if name == "load_case":
        from .case import load_case

        return load_case
    if name == "Simulation":
        from .simulation import Simulation

        return Simulation
    raise AttributeError(f"module 'mpmflow' has no attribute {name!r}")
