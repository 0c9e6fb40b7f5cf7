"""Volume and particle distribution: how far the approximate projection lets the water pack.

Recorded during the finest sloshing run (5 s) and the finest aspect-ratio-2 dam break
(1.0 s), at every output time, from the cell volume fractions f = (particle volume in the
cell) / (cell volume); the particles' volume is constant, so an incompressible material
keeps f at or below 1:

* **packed share**: the share of the cells holding material (f > 0) with f > 1.2, i.e. with
  20 or more of 16 particles' worth of volume;
* **wetted region volume**: the volume of the cells with f >= 1/2 (the f = 1/2 level also
  defines the front, the height and the VOF reference's surface), over the water's volume.
  It stays near 1 (within the half-cell resolution of the surface) when the water neither
  packs (falls below 1) nor loosens into a sparser arrangement of particles (rises above 1);
* **packing deficit** (table only): 1 - (sum over cells of min(f, 1) times the cell volume)
  / (water volume), exactly the volume packed into over-full cells;
* **interior mean f** (table and plot): the mean f over the interior cells, those whose
  eight neighbours all hold material. It is 1 for water that neither packs nor loosens and
  does not depend on how well the surface is resolved, which the wetted region does: in a
  violent flow every surface cell with f >= 1/2 counts in full.
"""

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..cells import bin_particles
from ..diagnostics.measures import WET
from ..simulation import Simulation
from .common import CaseResult, Row, fmt, markdown_table, pyplot, save
from .types import Context, FloatArray

# tolerances, fixed before the results were looked at
TOL_SHARE = {"sloshing": 0.01, "dam break": 0.05}
WHY_SHARE = {
    "sloshing": "a gentle flow: the volume correction should undo packing within a few steps, "
    "leaving at most 1 cell in 100 with 4 surplus particles",
    "dam break": "the impact and the overturning jet pack the particles; 5% of the cells is "
    "the upper bound of what the volume correction is designed to tolerate",
}
TOL_RATIO = {"sloshing": 0.01, "dam break": 0.03}
WHY_RATIO = {
    "sloshing": "1% of the volume is 2 mm of depth, a quarter of the wave amplitude 8 mm; the "
    "f = 1/2 surface of 40 columns resolves it",
    "dam break": "3% of the column is 0.06 a of height, below the 0.08 a height tolerance",
}


def packing(sim: Simulation) -> tuple[float, float, float, float]:
    """(packed share, wetted region ratio, packing deficit, interior mean f) of a state."""
    g = sim.grid
    theta = bin_particles(g, sim.particles).theta
    wet = theta > 0
    share = float(np.count_nonzero(theta > 1.2) / max(1, int(np.count_nonzero(wet))))
    region = float(np.count_nonzero(theta >= WET) * g.cell_volume / sim.volume0)
    deficit = float(1.0 - np.minimum(theta, 1.0).sum() * g.cell_volume / sim.volume0)
    f = theta.reshape(g.cells[1], g.cells[0])
    w = f > 0
    inner = np.zeros_like(w)
    inner[1:-1, 1:-1] = np.logical_and.reduce(
        [
            w[1 + dy : w.shape[0] - 1 + dy, 1 + dx : w.shape[1] - 1 + dx]
            for dy in (-1, 0, 1)
            for dx in (-1, 0, 1)
        ]
    )
    interior = float(f[inner].mean()) if inner.any() else float("nan")
    return share, region, deficit, interior


class Recorder:
    """An on_output callback that records (time, *packing(sim))."""

    def __init__(self, then: Callable[[Simulation], None] | None = None) -> None:
        self.rows: list[tuple[float, ...]] = []
        self.then = then

    def __call__(self, sim: Simulation) -> None:
        self.rows.append((sim.time, *packing(sim)))
        if self.then is not None:
            self.then(sim)

    def array(self) -> FloatArray:
        return np.array(self.rows, dtype=float).reshape(-1, 5)


def run(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("volume", "Volume and particle distribution")
    recorded = (context or {}).get("volume", {})
    lines = []
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for flow in ("sloshing", "dam break"):
        if flow not in recorded:
            continue
        label, rec = recorded[flow]
        a = rec.array()
        t, share, region, deficit, interior = a.T
        change = region - 1.0
        worst = float(change[np.argmax(np.abs(change))])
        res.rows.append(
            Row(
                "volume",
                f"{flow}: packed cells",
                f"largest share of wetted cells with f > 1.2 over 0-{t[-1]:g} s ({label})",
                float(share.max()),
                TOL_SHARE[flow],
                WHY_SHARE[flow],
                miss="a count per cell steps by a row of particles (a quarter of a cell): the "
                "flow strains the lattice of particles by a few percent and some cells "
                "hold 5 rows of 4 (1.25) while the material's volume is right; the same "
                "threshold on the volume correction's hat-kernel density reads 0-0.8% "
                "(the long-run case)",
            )
        )
        res.rows.append(
            Row(
                "volume",
                f"{flow}: wetted region",
                "largest |V(f >= 1/2) / V_water "
                f"- 1| over 0-{t[-1]:g} s ({label}; signed value shown)",
                worst,
                TOL_RATIO[flow],
                WHY_RATIO[flow],
                sense="|<=|",
                miss="the water loosens (value > 0) or packs (value < 0) faster than the volume "
                "correction brings it back",
            )
        )
        lines.append(
            [
                flow,
                label,
                fmt(share.max()),
                fmt(share[-1]),
                fmt(region.min()),
                fmt(region.max()),
                fmt(region[-1]),
                fmt(deficit.max()),
                fmt(interior.min()),
                fmt(interior[-1]),
            ]
        )
        ax[0].plot(t, 100 * share, label=f"{flow} ({label})")
        (line,) = ax[1].plot(t, region, label=f"wetted region, {flow} ({label})")
        ax[1].plot(t, interior, ":", color=line.get_color(), label=f"interior mean f, {flow}")
    ax[0].set_xlabel("t [s]")
    ax[0].set_ylabel("wetted cells with f > 1.2 [%]")
    ax[1].set_xlabel("t [s]")
    ax[1].set_ylabel("V(f >= 1/2) / V_water; interior mean f [-]")
    for a_ in ax:
        a_.legend()
    fig.tight_layout()
    save(fig, out / "volume.png")
    res.figures.append(
        (
            "volume.png",
            "Share of packed cells (left) and volume of the wetted region (right) against time.",
        )
    )
    res.text = (
        __doc__.split("\n", 2)[2].strip()
        + "\n\n"
        + markdown_table(
            [
                "flow",
                "run",
                "largest packed share",
                "packed share at the end",
                "wetted region / water volume: smallest",
                "largest",
                "at the end",
                "largest packing deficit",
                "interior mean f: smallest",
                "at the end",
            ],
            lines,
        )
    )
    return res
