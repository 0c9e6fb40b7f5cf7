"""Surface loads ([[loads]]): each node's share of a traction on a face of the material."""

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import load_case
from mpmflow.boundaries import loads
from mpmflow.errors import CaseError
from mpmflow.grid import Grid
from mpmflow.parallel.support import refusals


def test_the_nodes_share_the_whole_traction_on_the_face():
    """The shares are int_face N_i: they sum to the traction times the face's length, the
    nodes inside the face take h each, and a face that ends between nodes shares its end
    between the two nodes about it (here 0.03 m of a 0.025 m grid past x = 0.1)."""
    case = load_case(
        EXAMPLES / "terzaghi.toml",
        ['loads=[{axis="y", at=1.0, lower=[0.0], upper=[0.13], traction=[2e3, -1e4]}]'],
    )
    grid = Grid.of_case(case)
    f = loads.nodal(case, grid)
    x = grid.node_coordinates()
    on = np.abs(x[:, 1] - 1.0) < 1e-12
    assert np.all(f[~on] == 0.0)
    assert f[:, 1].sum() == pytest.approx(-1e4 * 0.13, rel=1e-12)
    assert f[:, 0].sum() == pytest.approx(2e3 * 0.13, rel=1e-12)
    inside = on & (x[:, 0] > 0.01) & (x[:, 0] < 0.09)
    assert f[inside, 1] == pytest.approx(-1e4 * 0.025, rel=1e-12)
    assert loads.nodal(load_case(EXAMPLES / "terzaghi.toml", ["loads=[]"]), grid) is None


def test_bad_loads_are_refused():
    def load(table):
        return load_case(EXAMPLES / "terzaghi.toml", [f"loads=[{table}]"])

    with pytest.raises(CaseError, match="a plane of the grid's nodes"):
        load('{axis="y", at=0.99, lower=[0.0], upper=[0.2], traction=[0.0, -1.0]}')
    with pytest.raises(CaseError, match="needs 2 components"):
        load('{axis="y", at=1.0, lower=[0.0], upper=[0.2], traction=[-1.0]}')
    with pytest.raises(CaseError, match="within the domain"):
        load('{axis="y", at=1.0, lower=[0.0], upper=[0.5], traction=[0.0, -1.0]}')
    with pytest.raises(CaseError, match="not an axis of a 2D domain"):
        load('{axis="z", at=1.0, lower=[0.0], upper=[0.2], traction=[0.0, -1.0]}')
    assert any("surface loads" in p for p in refusals(load_case(EXAMPLES / "terzaghi.toml")))


def test_a_load_off_the_material_stops_the_run():
    """A load on a node plane the material does not reach (here above the column's top, a
    cell beyond it) would act on nothing: the run stops and names where, rather than run
    unloaded."""
    from mpmflow import Simulation
    from mpmflow.errors import SimulationError

    table = '{axis="y", at=1.1, lower=[0.0], upper=[0.2], traction=[0.0, -1e4]}'
    sets = [f"loads=[{table}]", "time.end=0.4", "output.interval=0.2"]
    sim = Simulation(load_case(EXAMPLES / "terzaghi.toml", sets))
    with pytest.raises(SimulationError, match="acts on a node without material"):
        sim.run()
