"""mpmflow: incompressible free-surface flow with the material point method and Chorin's
projection (Kularathna & Soga 2017). SI units throughout.

    from mpmflow import load_case, Simulation
    summary = Simulation(load_case("examples/dam_break.toml"), out_dir="run").run()
"""

__version__ = "0.1.0"

from .case import load_case  # noqa: E402
from .simulation import Simulation  # noqa: E402

__all__ = ["load_case", "Simulation", "__version__"]
