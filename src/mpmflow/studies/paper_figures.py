"""Figures of the paper study (``studies.paper``): Fig. 2, 3 and 4 analogues as PNG files."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..plotting.mpl import pyplot
from .reference_data import MM_HEIGHT_AR2, VOF_AR2, G, load

if TYPE_CHECKING:  # paper.py runs the study and calls write_figures
    from .paper import Row, RunResult

A = 0.114  # m, width of both columns
MM_FRONT = "validation/martin_moyce_1952_n2eq2_a2.25in_front_table2.csv"
CRUCHAGA = "validation/cruchaga_2007_water_AR1_front_coarse_points_ethersph.csv"
COLOURS = {0.0114: "tab:green", 0.008: "tab:orange", 0.004: "tab:blue"}
STYLES = {"projection": "-", "real": ":", "reduced": "--"}


def _kind(row: Row) -> str:
    if row["scheme"] == "projection":
        return "projection"
    return "real" if row["bulk_modulus_pa"] >= 1e9 else "reduced"


def _plt() -> ModuleType:
    return pyplot("mpmflow study (its figures)")


def fig2(results: Sequence[RunResult], ar: str, path: Path) -> None:
    """Normalised column height and surge front against normalised time."""
    plt = _plt()
    fig, (ax_h, ax_f) = plt.subplots(1, 2, figsize=(13, 5), constrained_layout=True)
    tau = np.sqrt(G / A)
    if ar == "2":
        vof, mm_h, mm_f = load(VOF_AR2), load(MM_HEIGHT_AR2), load(MM_FRONT)
        ax_h.plot(vof[:, 0] * tau, vof[:, 2] / (2 * A), "k-", lw=3, alpha=0.3, label="VOF")
        ax_h.plot(mm_h[:, 0], mm_h[:, 1], "ks", mfc="none", label="Martin & Moyce, Table 6")
        ax_f.plot(vof[:, 0] * tau * np.sqrt(2), vof[:, 1] / A, "k-", lw=3, alpha=0.3, label="VOF")
        ax_f.plot(mm_f[:, 0], mm_f[:, 1], "ks", mfc="none", label="Martin & Moyce, Table 2")
    else:
        cr = load(CRUCHAGA)
        ax_f.plot(
            cr[:, 0] * tau * np.sqrt(2),
            cr[:, 1],
            "k^",
            mfc="none",
            label="Cruchaga et al. (coarse points)",
        )
    height0 = 2 * A if ar == "2" else A
    for r in results:
        if r.row["ar"] != ar:
            continue
        style = dict(
            color=COLOURS.get(r.row["spacing_m"], "k"),
            ls=STYLES[_kind(r.row)],
            label=r.row["label"],
            lw=1.3,
        )
        ax_h.plot(r.t * tau, r.height / height0, **style)
        ax_f.plot(r.t * tau * np.sqrt(2), r.front / A, **style)
    ax_h.set(
        xlabel="t sqrt(g/a)",
        ylabel="column height at the left wall / initial height",
        title=f"(a) column height, aspect ratio {ar}",
    )
    ax_f.set(
        xlabel="t sqrt(2g/a)",
        ylabel="surge front / a",
        ylim=(0.9, 4.0),
        title=f"(b) surge front, aspect ratio {ar}",
    )
    ax_f.legend(fontsize=7, loc="lower right")
    ax_h.legend(fontsize=7, loc="lower left")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _finest(results: Sequence[RunResult], ar: str) -> list[RunResult]:
    sel = [r for r in results if r.row["ar"] == ar]
    h = min(r.row["spacing_m"] for r in sel)
    return [r for r in sel if r.row["spacing_m"] == h]


def fig3(results: Sequence[RunResult], ar: str, path: Path, vmax: float) -> None:
    """Particle pressure at 0.1 s intervals, each scheme at the finest mesh."""
    plt = _plt()
    runs = _finest(results, ar)
    times = [round(0.1 * k, 1) for k in range(1, 11)]
    fig, axes = plt.subplots(
        len(times),
        len(runs),
        figsize=(4.2 * len(runs), 1.9 * len(times)),
        constrained_layout=True,
        squeeze=False,
    )
    sc = None
    for j, r in enumerate(runs):
        for i, t in enumerate(times):
            ax = axes[i, j]
            ax.set(
                xlim=(0, 0.42),
                ylim=(0, 0.24 if ar == "2" else 0.14),
                aspect="equal",
                xticks=[],
                yticks=[],
            )
            if i == 0:
                ax.set_title(r.row["label"], fontsize=9)
            if j == 0:
                ax.set_ylabel(f"{t:.1f} s")
            if t not in r.fields:
                ax.text(0.21, 0.06, "not reached\nin the budget", ha="center", fontsize=8)
                continue
            x, p = r.fields[t]
            sc = ax.scatter(
                x[:, 0], x[:, 1], c=p, s=0.15, cmap="viridis", vmin=0, vmax=vmax, rasterized=True
            )
    if sc is not None:
        fig.colorbar(sc, ax=axes, label="particle pressure (Pa)", shrink=0.4)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def surface_profile(
    x: NDArray[np.float64], width: float = 0.42, bins: int = 84
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Free-surface profile: the highest particle in each of ``bins`` columns (m)."""
    edges = np.linspace(0.0, width, bins + 1)
    k = np.clip(np.digitize(x[:, 0], edges) - 1, 0, bins - 1)
    top = np.full(bins, np.nan)
    np.fmax.at(top, k, x[:, 1])
    return 0.5 * (edges[1:] + edges[:-1]), top


def fig4(results: Sequence[RunResult], ar: str, path: Path) -> None:
    """Free-surface profiles at 0.1 s intervals, each scheme at the finest mesh."""
    plt = _plt()
    runs = _finest(results, ar)
    times = [round(0.1 * k, 1) for k in range(1, 11)]
    fig, axes = plt.subplots(5, 2, figsize=(11, 10), constrained_layout=True)
    for ax, t in zip(axes.T.ravel(), times):
        for r in runs:
            if t in r.fields:
                xc, top = surface_profile(r.fields[t][0])
                ax.plot(xc, top, ls=STYLES[_kind(r.row)], label=r.row["label"], lw=1.2)
        ax.set(xlim=(0, 0.42), ylim=(0, 0.3 if ar == "2" else 0.2), title=f"t = {t:.1f} s")
    axes[0, 0].legend(fontsize=7)
    fig.supxlabel("x (m)")
    fig.supylabel("highest particle (m)")
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_figures(results: Sequence[RunResult], out: str | Path) -> None:
    out = Path(out)
    for ar in sorted({r.row["ar"] for r in results}, reverse=True):
        fig2(results, ar, out / f"fig2_height_front_ar{ar}.png")
        fig3(results, ar, out / f"fig3_pressure_ar{ar}.png", vmax=2300 if ar == "2" else 1200)
        fig4(results, ar, out / f"fig4_surface_ar{ar}.png")
