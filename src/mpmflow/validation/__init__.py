"""Validation suite: mpmflow's accuracy as numbers against analytic and measured data.

    mpmflow validate --out DIR [--quick] [--case NAME ...]

runs the cases below, compares each with its reference and writes DIR/README.md (the
summary table first: case, quantity, error measure, value, tolerance, pass/miss, and the
tolerance's justification; then one section per case with plots and the measures'
definitions) and DIR/summary.csv. ``--quick`` runs the small versions the test suite uses.

Each case is a module with ``run(out, quick, context) -> CaseResult``; ``context`` carries
what a later case needs from an earlier one (the volume measures are recorded during the
sloshing and dam-break runs).
"""

import time as _time
from collections.abc import Callable, Collection, Sequence
from pathlib import Path
from typing import Protocol

from ..errors import CaseError, SimulationError
from . import (
    bodies,
    channel_flows,
    dam_break,
    dam_break_ar1,
    footing,
    frictional_column,
    granular_3d,
    granular_cd,
    hydrostatic,
    lobovsky,
    long_run,
    materials,
    saturated,
    slamming,
    sloshing,
    solids,
    spheric,
    three_d,
    time_step_study,
    volume,
)
from .common import EXAMPLES, CaseResult, Row
from .types import Context


class CaseRun(Protocol):
    """A case's ``run(out, quick, context)``."""

    def __call__(self, out: Path, quick: bool, context: Context | None) -> CaseResult: ...


CASES: dict[str, CaseRun] = {
    "hydrostatic": hydrostatic.run,
    "sloshing": sloshing.run,
    "dam_break": dam_break.run,
    "dam_break_ar1": dam_break_ar1.run_ar1,
    "time_step_study": time_step_study.run,
    "lobovsky": lobovsky.run,
    "volume": volume.run,
    "long_run": long_run.run,
    "three_d": three_d.run,
    "spheric": spheric.run,
    "viscous_wave": materials.run_wave,
    "granular_collapse": materials.run_collapse,
    "granular_collapse_3d": granular_3d.run,
    "granular_collapse_cd": granular_cd.run,
    "bingham_slump": materials.run_slump,
    "poiseuille": channel_flows.run_poiseuille,
    "bingham_plug": channel_flows.run_plug,
    "mu_i_layer": channel_flows.run_layer,
    "cantilever": solids.run_cantilever,
    "prandtl_footing": footing.run_footing,
    "bui_collapse": frictional_column.run_column,
    "heave_cylinder": bodies.run,
    "wave_maker": bodies.run_wave_maker,
    "floating_bodies": bodies.run_floating_bodies,
    "wedge_entry": slamming.run_wedge_entry,
    "terzaghi": saturated.run_terzaghi,
    "mandel": saturated.run_mandel,
    "seabed": saturated.run_seabed,
}
NEEDS = {"volume": ("sloshing", "dam_break")}
EXAMPLE_FILES = {
    "hydrostatic": ("hydrostatic.toml",),
    "sloshing": ("sloshing.toml",),
    "dam_break": ("dam_break.toml",),
    "dam_break_ar1": ("dam_break_ar1.toml",),
    "time_step_study": ("dam_break.toml",),
    "lobovsky": ("lobovsky.toml",),
    "long_run": ("sloshing.toml", "dam_break.toml"),
    "three_d": ("hydrostatic_3d.toml", "dam_break_3d.toml", "dam_break.toml"),
    "spheric": ("spheric_test2.toml",),
    "viscous_wave": ("sloshing.toml",),
    "granular_collapse": ("granular_collapse.toml",),
    "granular_collapse_3d": ("granular_collapse.toml",),
    "granular_collapse_cd": ("granular_collapse.toml",),
    "bingham_slump": ("bingham_slump.toml",),
    "poiseuille": ("poiseuille_film.toml",),
    "bingham_plug": ("bingham_plug.toml",),
    "mu_i_layer": ("mu_i_layer.toml",),
    "cantilever": ("cantilever.toml",),
    "prandtl_footing": ("footing.toml",),
    "bui_collapse": ("bui_column.toml",),
    "heave_cylinder": ("heave_cylinder.toml",),
    "wave_maker": ("wave_maker.toml",),
    "floating_bodies": ("floating_box.toml", "heave_cylinder.toml"),
    "wedge_entry": ("wedge_entry.toml",),
    "terzaghi": ("terzaghi.toml",),
    "mandel": ("mandel.toml",),
    "seabed": ("seabed.toml",),
}  # the examples/ files each runs


def case_names(cases: Collection[str] | None = None) -> list[str]:
    """The cases to run, in order: ``cases`` (all by default) and those they need."""
    names = list(CASES) if not cases else [c for c in CASES if c in cases]
    for name in list(names):
        for need in NEEDS.get(name, ()):
            if need not in names:
                names.insert(names.index(name), need)
    return names


def missing_examples(cases: Collection[str] | None = None) -> list[Path]:
    """The example case files the cases would run that are not there."""
    files = dict.fromkeys(f for n in case_names(cases) for f in EXAMPLE_FILES.get(n, ()))
    return [EXAMPLES / f for f in files if not (EXAMPLES / f).is_file()]


def _missing_text(missing: Sequence[Path]) -> str:
    return (
        "mpmflow validate runs the case files in the examples/ folder of a source "
        f"checkout, and {', '.join(str(p) for p in missing)} "
        f"{'is' if len(missing) == 1 else 'are'} missing. Run it from a checkout of "
        "mpmflow installed with `pip install -e .` (as `make setup` does)."
    )


def run_validation(
    out: str | Path,
    quick: bool = False,
    cases: Collection[str] | None = None,
    progress: Callable[[CaseResult], object] | None = None,
) -> tuple[list[CaseResult], dict[str, int]]:
    """Run the cases (all by default) into ``out``; returns (results, counts)."""
    from .report import check_report_folder, write_report

    out = Path(out)
    check_report_folder(out)
    missing = missing_examples(cases)
    if missing:
        raise CaseError(_missing_text(missing))
    out.mkdir(parents=True, exist_ok=True)
    names = case_names(cases)
    context: Context = {}
    results: list[CaseResult] = []
    t0 = _time.perf_counter()
    for name in names:
        t1 = _time.perf_counter()
        try:
            res = CASES[name](out, quick=quick, context=context)
        except SimulationError as err:  # the report says so; the other cases go on
            res = CaseResult(
                name,
                name,
                rows=[
                    Row(
                        name,
                        "run",
                        "completed",
                        float("nan"),
                        0,
                        "a validation run must complete",
                        miss=str(err),
                    )
                ],
                text=f"Failed: {err}",
            )
        res.wall_s = _time.perf_counter() - t1
        results.append(res)
        if progress is not None:
            progress(res)
    counts = write_report(out, results, quick, _time.perf_counter() - t0)
    return results, counts
