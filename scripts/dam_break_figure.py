"""The README's results figure: the paper's dam break at its three meshes against the VOF
reference and Martin & Moyce (1952), and particle pressure at 0.1, 0.2 and 0.3 s.

    python scripts/dam_break_figure.py --out docs/dam_break.png     (about 15 s on 2 cores)
"""

import argparse
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import meshio  # noqa: E402
import numpy as np  # noqa: E402

from mpmflow import Simulation, load_case  # noqa: E402
from mpmflow.studies.reference_data import MM_HEIGHT_AR2, VOF_AR2, G, load  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
A = 0.114
MESHES = [("0.0114", "0.01"), ("0.008", "0.001"), ("0.004", "0.001")]
MM_FRONT = "validation/martin_moyce_1952_n2eq2_a2.25in_front_table2.csv"


def run(spacing, dt, out):
    case = load_case(
        ROOT / "examples/dam_break.toml",
        [
            f"grid.spacing={spacing}",
            f"time.dt={dt}",
            "time.end=0.5",
            "output.snapshot_interval=0.1",
        ],
    )
    sim = Simulation(case, out)
    sim.run()
    return sim


def snapshot(folder, time):
    for d in ET.parse(folder / "particles.pvd").getroot().iter("DataSet"):
        if abs(float(d.get("timestep")) - time) < 1e-9:
            return meshio.read(folder / d.get("file"))
    raise KeyError(time)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "docs" / "dam_break.png"))
    args = ap.parse_args()
    fig = plt.figure(figsize=(12, 7.5), constrained_layout=True)
    grid = fig.add_gridspec(2, 3)
    ax_h = fig.add_subplot(grid[0, :2])
    ax_f = fig.add_subplot(grid[0, 2])
    vof = load(VOF_AR2)
    mm_h = load(MM_HEIGHT_AR2)
    mm_f = load(MM_FRONT)
    tau = np.sqrt(G / A)
    ax_h.plot(
        vof[:, 0] * tau,
        vof[:, 2] / (2 * A),
        "k-",
        lw=2.5,
        alpha=0.35,
        label="VOF (interFoam, 0.004 m)",
    )
    ax_h.plot(mm_h[:, 0], mm_h[:, 1], "ks", mfc="none", label="Martin & Moyce, Table 6")
    ax_f.plot(vof[:, 0] * tau * np.sqrt(2), vof[:, 1] / A, "k-", lw=2.5, alpha=0.35, label="VOF")
    ax_f.plot(mm_f[:, 0], mm_f[:, 1], "ks", mfc="none", label="Martin & Moyce, Table 2")
    with tempfile.TemporaryDirectory() as tmp:
        for (spacing, dt), colour in zip(MESHES, ["tab:green", "tab:orange", "tab:blue"]):
            out = Path(tmp) / spacing
            sim = run(spacing, dt, out)
            t = sim.series("time")
            label = f"mpmflow, {spacing} m, dt = {dt} s"
            ax_h.plot(t * tau, sim.series("height") / (2 * A), color=colour, label=label)
            ax_f.plot(t * tau * np.sqrt(2), sim.series("front") / A, color=colour, label=label)
        fine = Path(tmp) / "0.004"
        for k, time in enumerate((0.1, 0.2, 0.3)):
            ax = fig.add_subplot(grid[1, k])
            mesh = snapshot(fine, time)
            sc = ax.scatter(
                mesh.points[:, 0],
                mesh.points[:, 1],
                c=mesh.point_data["pressure"],
                s=0.6,
                cmap="viridis",
                vmin=0,
                vmax=2300,
                rasterized=True,
            )
            ax.set(
                xlim=(0, 0.42),
                ylim=(0, 0.25),
                aspect="equal",
                xlabel="x (m)",
                title=f"t = {time:.1f} s, 0.004 m mesh",
            )
            if k == 0:
                ax.set_ylabel("y (m)")
        fig.colorbar(sc, ax=fig.axes[-3:], label="particle pressure (Pa)", shrink=0.8)
    ax_h.set(
        xlabel="tau = t sqrt(g/a)",
        ylabel="height at left wall / (2a)",
        xlim=(0, 4.2),
        ylim=(0, 1.05),
        title="Column height (a = 0.114 m)",
    )
    ax_f.set(
        xlabel="T = t sqrt(2g/a)",
        ylabel="surge front / a",
        xlim=(0, 3.6),
        ylim=(1, 3.8),
        title="Surge front",
    )
    ax_h.legend(fontsize=8)
    ax_f.legend(fontsize=7, loc="upper left")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
