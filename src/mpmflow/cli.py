"""Command line: ``mpmflow run CASE.toml --out DIR [--set key=value ...]`` and friends.

Exit codes: 0 success; 2 invalid input (case file, settings, command line, a case too large
for the memory, an output folder in use by another run: nothing was run); 3 the simulation
failed (pressure solve, blow-up); 130 interrupted by Ctrl-C (SIGINT), 143 by SIGTERM (after
the first signal a checkpoint is written: continue with --restart; a second signal stops at
once without one; before the run starts, a signal stops at once); 141 the reader of the
output went away (a closed pipe).
"""

import argparse
import json
import shlex
import sys
import textwrap
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ._version import __version__
from .errors import CaseError, MpmflowError
from .interrupts import EarlySignals, EarlyStop, StopNow, exit_code
from .output import check_out_dir as _check_out_dir
from .output import os_error, silence_stdout

if TYPE_CHECKING:
    from .validation.common import CaseResult

# Ctrl-C and SIGTERM from the moment the command starts: before the run's own handlers
# (interrupts.stop_on_signals) take over, a signal stops at once with a message
early = EarlySignals()

DESCRIPTION = """\
mpmflow simulates incompressible free-surface flow (dam breaks, sloshing) with the material
point method, solving the pressure implicitly with Chorin's projection (Kularathna & Soga,
2017). Cases are TOML files; all quantities are SI (m, s, kg, Pa)."""

RUN_HELP = """\
Run a case and write its outputs to DIR:
  timeseries.csv   one row per output.interval: time [s], front [m], height [m], ...
  summary.json     status, steps, particles, wall_seconds, solver statistics, the energy
                   check, resolved case
  particles.pvd    ParaView time series of particle snapshots (particles_NNNNNN.vtu; on
                   several ranks particles_NNNNNN.pvtu naming one piece a rank)

Any case key can be overridden with --set, using the dotted names of the case-file
reference (`mpmflow keys` lists them), e.g.
  mpmflow run examples/dam_break.toml --out run --set grid.spacing=0.008 --set time.end=0.3
Values are TOML: numbers, true/false, [lists], "strings" (bare words are taken as strings).

Checkpoints (checkpoint_NNNNNNNNN.npz, every checkpoint.interval of simulated time, at the
end, and on Ctrl-C or SIGTERM) let a run continue where it stopped:
  mpmflow run examples/dam_break.toml --out run --restart
continues from the latest checkpoint in run/ with the same settings, bit for bit as if
it had not stopped; --set time.end=... with a later time extends a finished run."""


EPILOG = """\
examples:
  mpmflow run examples/dam_break.toml --out runs/dam_break
  mpmflow plot runs/dam_break                     (figures into runs/dam_break/plots)
  mpmflow run examples/hydrostatic.toml --out runs/still --set solver.formulation=paper
  mpmflow validate --out runs/validation
  mpmflow keys

exit codes: 0 success, 2 invalid input (nothing was run: a bad case or setting, a case
too large for this machine's memory, an output folder in use by another run), 3 the run
failed (see summary.json), 130 interrupted by Ctrl-C, 143 by SIGTERM (after the first
signal a checkpoint is written: continue with --restart; a second signal stops at once
without one), 141 the output pipe was closed (mpmflow keys | head)."""


# mpmflow.validation.CASES, named here so that --help does not import the suite (a test
# checks that the two agree)
VALIDATION_CASES = (
    "hydrostatic",
    "sloshing",
    "dam_break",
    "dam_break_ar1",
    "time_step_study",
    "lobovsky",
    "volume",
    "long_run",
    "three_d",
    "spheric",
    "viscous_wave",
    "granular_collapse",
    "granular_collapse_3d",
    "granular_collapse_cd",
    "bingham_slump",
    "poiseuille",
    "bingham_plug",
    "mu_i_layer",
    "cantilever",
    "prandtl_footing",
    "bui_collapse",
    "heave_cylinder",
    "wave_maker",
    "floating_bodies",
    "wedge_entry",
    "terzaghi",
    "mandel",
    "seabed",
)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="mpmflow",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"mpmflow {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    r = sub.add_parser(
        "run",
        help="run a case file",
        description=RUN_HELP,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    r.add_argument("case", metavar="CASE.toml", help="case file (TOML)")
    r.add_argument(
        "--out",
        "-o",
        metavar="DIR",
        default=None,
        help="output folder (created if needed); required unless --dry-run",
    )
    r.add_argument(
        "--set",
        "-s",
        metavar="KEY=VALUE",
        action="append",
        default=[],
        dest="overrides",
        help="override a case key (repeatable)",
    )
    r.add_argument(
        "--overwrite", action="store_true", help="replace the results of an earlier run in DIR"
    )
    r.add_argument(
        "--restart",
        action="store_true",
        help="continue the run in DIR from its latest checkpoint (same settings; "
        "a later time.end extends it)",
    )
    r.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    r.add_argument(
        "--dry-run",
        action="store_true",
        help="check the case and print what the run would be and the memory it needs, "
        "without running it, making its particles or writing anything (exit 0 also when "
        "it would not fit this machine: it says so)",
    )
    r.add_argument(
        "--ranks",
        type=int,
        metavar="N",
        default=None,
        help="with --dry-run: the memory of each rank of the run on N MPI processes "
        "(mpirun -n N), by term (particles and grid split as the run splits them, the "
        "halo, the ghost layer, PETSc's matrix); default: the processes it was started on",
    )
    st = sub.add_parser(
        "study",
        help="run the paper's study (Table 1, Figs. 2-4) with both schemes",
        description="Run the study of Kularathna & Soga (2017): the dam break at the paper's "
        "three meshes with the projection scheme, the explicit scheme at K = 2.2 GPa (for as "
        "long as --budget allows per run) and the explicit scheme at a reduced K, for the "
        "aspect-ratio-2 and aspect-ratio-1 columns. Writes study.md, study.csv, the figures "
        "and each run's outputs (DIR/runs/).",
    )
    st.add_argument("name", choices=["paper"], help="the study to run")
    st.add_argument("--out", "-o", metavar="DIR", required=True, help="output folder")
    st.add_argument(
        "--budget",
        type=float,
        default=240.0,
        metavar="S",
        help="wall seconds per explicit run at the real K (default 240: the "
        "whole study then takes about 15 minutes on 2 cores)",
    )
    st.add_argument(
        "--quick",
        action="store_true",
        help="coarsest mesh, aspect ratio 2 only, to 0.3 s (a smoke test)",
    )
    pl = sub.add_parser(
        "plot",
        help="plot a run's time series, probes, particle snapshots and an animation",
        description="Plot the outputs of a run (needs matplotlib, and scikit-image for 3D: "
        "pip install 'mpmflow[plot]'): timeseries.png (front and height, energies, largest speed and "
        "pressure, pressure noise, volume ratio), probes.png (with [[probes]]: pressures and "
        "levels against time, over the measured series named by probes.N.data), "
        "snapshots/particles_NNNNNN.png and "
        "snapshots.png (particles coloured by pressure; in 3D the mid-width slice), "
        "animation.gif (the snapshots; set output.snapshot_interval for more frames) and, in "
        "3D, snapshots/surface_NNNNNN.png and surfaces.png (the water's surface, where the "
        "volume fraction is 1/2, and the obstacles).",
    )
    pl.add_argument("run_dir", metavar="DIR", help="the --out folder of a run")
    pl.add_argument(
        "--out",
        "-o",
        metavar="DIR2",
        default=None,
        help="folder for the figures (default: DIR/plots)",
    )
    v = sub.add_parser(
        "validate",
        help="run the validation suite and write its report",
        description="Run the validation cases (hydrostatic column, standing-wave sloshing, "
        "dam breaks of aspect ratio 2 and 1 at the paper's meshes, time-step independence, "
        "Lobovsky et al. 2014, volume and particle distribution, long runs: 20 s of sloshing and "
        "10 s of dam break for volume and energy), compare each with its "
        "analytic or measured reference, and write DIR/README.md (summary table: case, "
        "quantity, error measure, value, tolerance, pass/miss; one section per case with "
        "plots) and DIR/summary.csv; a README.md in DIR that it did not write is never replaced. "
        "Needs matplotlib. The full run takes 60 to 85 minutes on 2 cores (83.5 on 2026-11-28: SPHERIC 37, the time-step study 11).",
        epilog="The reference data are read from ../shared/data (or $MPMFLOW_DATA).",
    )
    v.add_argument("--out", "-o", metavar="DIR", required=True, help="report folder")
    v.add_argument(
        "--quick",
        action="store_true",
        help="the small versions the test suite runs (about 3 minutes on 2 cores)",
    )
    v.add_argument(
        "--case",
        action="append",
        default=[],
        metavar="NAME",
        dest="cases",
        help="run only this case (repeatable): " + ", ".join(VALIDATION_CASES),
    )
    k = sub.add_parser(
        "keys",
        help="list every case key with its meaning and default",
        description="List every case-file key (dotted name), its default and its meaning.",
    )
    k.add_argument("--json", action="store_true", help="machine-readable output")
    k.add_argument(
        "--markdown", action="store_true", help="the reference table of docs/reference.md"
    )
    return p


# the commands read the parsed arguments (argparse.Namespace: Any by attribute) and the
# progress bar is tqdm's (no type information): Any at both seams
def _progress_bar(
    end: float, quiet: bool, start: float = 0.0, step: int = 0
) -> tuple[Any, Callable[[float, int, float], None] | None]:
    """A tqdm bar over simulated time with the step count, and its update callback.
    ``start``, ``step``: where the run begins (a restart's time and step)."""
    if quiet:
        return None, None
    from tqdm import tqdm

    bar = tqdm(
        total=end,
        initial=start,
        unit="s",
        unit_scale=False,
        dynamic_ncols=True,
        file=sys.stderr,
        bar_format="{l_bar}{bar}| t = {n:.3f}/{total:.3f} s [{elapsed}<{remaining}]{postfix}",
        postfix=f"step {step}",
    )
    last = [start]

    def update(t: float, step: int, end_: float) -> None:
        # the step count before the time: update() draws the bar, and a count set after it
        # was drawn beside the next output's time (one output interval behind)
        bar.set_postfix_str(f"step {step}", refresh=False)
        bar.update(t - last[0])
        last[0] = t

    return bar, update


def _resume_command(args: argparse.Namespace) -> str:
    words = ["mpmflow", "run", args.case, "--out", args.out, "--restart"]
    for item in args.overrides:
        words += ["--set", item]
    return " ".join(shlex.quote(str(w)) for w in words)


def _dry_run(args: argparse.Namespace) -> int:
    """``mpmflow run CASE --dry-run [--ranks N]``: the case checked, what the run would be
    and its memory, one process's or each rank's; nothing allocated, run or written."""
    from . import memory
    from .case import load_case
    from .grid import Grid
    from .parallel.comm import launched_rank, launched_size

    case = load_case(args.case, args.overrides)
    ranks = args.ranks if args.ranks is not None else launched_size()
    one = memory.estimate(case)
    grid = Grid.covering(case.domain.size, case.grid.spacing)
    budget, source = memory.available()
    count = one.particles
    particles = f"{count:,}" if isinstance(count, int) else f"{count:.3g}"
    steps = case.time.end / case.time.dt if isinstance(case.time.dt, float) else None
    lines = [
        f"{case.title + ': ' if case.title else ''}{particles} particles, "
        + " x ".join(str(n) for n in grid.cells)
        + f" cells of {case.grid.spacing:g} m"
        + (f", about {steps:,.0f} steps" if steps is not None else "")
        + f" to t = {case.time.end:g} s (about {memory.size(one.disk_bytes)} on disk)"
    ]
    if ranks == 1:
        lines.append(f"memory on one process: {one.text()}")
        need, here = one.total, 1
    else:
        from .parallel import memory as per_rank

        est = per_rank.estimate(case, ranks)
        lines += est.lines(every=16)
        need, here = est.here * est.largest.total, est.here
    fits = "fits" if need <= budget else "does not fit"
    lines.append(
        f"this machine can give {memory.size(budget)} ({source}): "
        + (f"{here} of the ranks on it need {memory.size(need)}; " if here > 1 else "")
        + f"the run {fits} here"
    )
    if launched_rank() == 0:
        print("\n".join(f"mpmflow: {line}" for line in lines))
    return 0


def _run(args: argparse.Namespace) -> int:
    if args.dry_run:
        return _dry_run(args)
    if args.ranks is not None:
        raise CaseError(
            f"--ranks {args.ranks} goes with --dry-run (the memory of a run on that many "
            "processes, without running it). To run on N processes, start the run with "
            "mpirun -n N .venv-mpi/bin/mpmflow run CASE --out DIR."
        )
    if args.out is None:
        raise CaseError(
            "mpmflow run needs --out DIR, the folder for the run's outputs (or --dry-run "
            "to check the case and print its memory without running it)."
        )
    with early.deferred():  # the compiled extensions load here
        from .case import load_case
        from .interrupts import stop_on_signals
        from .output.folder import CLI_HINTS
        from .simulation import Simulation
    early.check()

    case = load_case(args.case, args.overrides)
    early.check()
    out = Path(args.out)
    _check_out_dir(args.out, create=False)
    if args.restart and args.overwrite:
        raise CaseError(
            "--restart continues the run in --out and --overwrite replaces it; give one of them."
        )
    from .parallel.comm import launched_size

    rank0 = True  # the process that speaks (one process, or rank 0 of an MPI run)
    if launched_size() > 1:  # mpirun: every rank steps the case, rank 0 writes
        from .parallel.comm import world
        from .parallel.run import start

        sim = start(case, out, args.restart, args.overwrite, CLI_HINTS)
        rank0 = world().rank == 0
        args.quiet = args.quiet or not rank0
    elif args.restart:
        if not out.is_dir():
            raise CaseError(
                f"--restart: --out {out} does not exist; give the folder of the "
                "run to continue, or run without --restart."
            )
        sim = Simulation.resume(case, out, hints=CLI_HINTS)
    else:
        sim = Simulation(case, out, overwrite=args.overwrite)
        early.check()
        sim.claim(CLI_HINTS)
    with sim:  # releases the folder if anything below fails before the run
        if args.restart and rank0:
            print(
                f"mpmflow: continuing from {sim.resumed_from} (t = {sim.time:.6g} s, step "
                f"{sim.steps})",
                file=sys.stderr,
            )
        if not args.quiet:
            for line in sim.describe():
                print(f"mpmflow: {line}", file=sys.stderr)
        for note in sim.notices if rank0 else []:
            print(f"mpmflow: note: {note}", file=sys.stderr)
        early.check()
        bar, update = _progress_bar(case.time.end, args.quiet, start=sim.time, step=sim.steps)
        sim.progress = update
        told = len(sim.notices)  # those the run adds are told at its end
        try:
            with stop_on_signals(sim):
                summary = sim.run()
        finally:
            if bar is not None:
                bar.close()
            early.phase = "after"
    if summary["status"] == "interrupted":
        print(
            f"mpmflow: interrupted at t = {summary['time']:.6g} s (step {summary['steps']}); "
            f"checkpoint {out / summary['last_checkpoint']}. Resume with: "
            f"{_resume_command(args)}",
            file=sys.stderr,
        )
        assert sim.stop_signal is not None  # "interrupted" with a summary: stop_on_signal's
        return exit_code(sim.stop_signal)
    if not args.quiet:
        print(
            f"mpmflow: {summary['steps']} steps, {summary['particles']} particles, "
            f"{summary['wall_seconds']:.2f} s wall; results in {out}",
            file=sys.stderr,
        )
    mpi = summary.get("mpi")
    if mpi and not args.quiet:
        print(
            f"mpmflow: {mpi['ranks']} ranks: particles {min(mpi['particles'])}-"
            f"{max(mpi['particles'])} a rank (balance {mpi['balance']:.2f}, split "
            f"{mpi['splits']} time{'s' if mpi['splits'] > 1 else ''}), steps "
            f"{max(mpi['step_seconds']):.2f} s, of which the pressure ({mpi['pressure']}) "
            f"{max(mpi['solve_seconds']):.2f} s on the slowest rank",
            file=sys.stderr,
        )
    for note in sim.notices[told:] if rank0 else []:
        print(f"mpmflow: note: {note}", file=sys.stderr)
    if sim.fallbacks and rank0:
        print(f"mpmflow: note: {sim.fallbacks.line()}", file=sys.stderr)
    return 0


def _study(args: argparse.Namespace) -> int:
    from .studies.paper import run_study

    if not args.budget > 0:
        raise CaseError(
            f"--budget {args.budget:g}: give a positive number of seconds, e.g. --budget 240."
        )
    out = Path(args.out)
    _check_out_dir(args.out)

    def report(row: dict[str, Any]) -> None:
        print(
            f"mpmflow: {row['label']} (aspect ratio {row['ar']}): {row['steps']} steps to "
            f"t = {row['time_reached_s']:.3g} s in {row['wall_s']:.1f} s wall "
            f"[{row['status']}]",
            file=sys.stderr,
        )

    run_study(
        out, budget=args.budget, quick=args.quick, end=0.3 if args.quick else 1.0, progress=report
    )
    print(f"mpmflow: study written to {out}/study.md", file=sys.stderr)
    return 0


def _plot(args: argparse.Namespace) -> int:
    from .plotting.figures import plot_run

    notes: list[str] = []
    written = plot_run(args.run_dir, args.out, notes)
    for note in notes:
        print(f"mpmflow: note: {note}", file=sys.stderr)
    print(f"mpmflow: wrote {len(written)} figures to {written[0].parent}", file=sys.stderr)
    return 0


def _validate(args: argparse.Namespace) -> int:
    from .plotting.mpl import have_matplotlib
    from .studies.reference_data import data_dir

    unknown = [c for c in args.cases if c not in VALIDATION_CASES]
    if unknown:
        raise CaseError(
            f"--case {unknown[0]}: unknown validation case; choose from "
            + ", ".join(VALIDATION_CASES)
            + "."
        )
    out = Path(args.out)
    _check_out_dir(args.out, create=False)
    # everything the cases need, checked before minutes of runs: matplotlib (the plots),
    # the reference data, the example case files, and a folder whose README.md is ours
    have_matplotlib("mpmflow validate")
    if not args.cases or "spheric" in args.cases:
        from .plotting.surface import need_skimage

        need_skimage("mpmflow validate (the SPHERIC case's 3D pictures)")
    try:
        data_dir()
    except FileNotFoundError as err:
        raise CaseError(str(err)) from None
    from .validation import _missing_text, missing_examples, run_validation
    from .validation.report import check_report_folder

    missing = missing_examples(args.cases)
    if missing:
        raise CaseError(_missing_text(missing))
    check_report_folder(out)
    _check_out_dir(args.out)

    def report(res: "CaseResult") -> None:  # quoted: imported for the type checker only
        misses = sum(r.status == "miss" for r in res.rows)
        print(
            f"mpmflow: {res.title}: {len(res.rows)} rows, {misses} missed, {res.wall_s:.0f} s",
            file=sys.stderr,
        )

    _, counts = run_validation(out, quick=args.quick, cases=args.cases, progress=report)
    print(
        f"mpmflow: {counts['pass']} rows pass, {counts['miss']} miss"
        + (f", {counts['n/a']} not measurable" if counts["n/a"] else "")
        + f"; report in {out}/README.md",
        file=sys.stderr,
    )
    return 0


def _keys(args: argparse.Namespace) -> int:
    from .case import key_reference, reference_markdown

    rows = key_reference()
    if args.markdown:
        print(reference_markdown())
        return 0
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    for row in rows:
        default = "required" if row["required"] else f"default {row['default']}"
        print(f"{row['key']}  ({default})")
        print(textwrap.indent(textwrap.fill(row["description"], 84), "    "))
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    with early.installed():
        try:
            return _main(argv)
        except BrokenPipeError:  # our reader went away (keys | head -1): quiet, as SIGPIPE
            silence_stdout()
            return 141
        except OSError as err:  # an output file or stdout (a full disk, too long a name)
            print(f"mpmflow: error: {os_error(err)}", file=sys.stderr)
            return 2


def _main(argv: Sequence[str] | None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    early.check()
    try:
        if args.command == "run":
            return _run(args)
        if args.command == "study":
            return _study(args)
        if args.command == "plot":
            return _plot(args)
        if args.command == "validate":
            return _validate(args)
        return _keys(args)
    except MpmflowError as err:
        print(f"mpmflow: error: {err}", file=sys.stderr)
        return err.exit_code
    except StopNow as err:
        print(
            f"mpmflow: stopped at once by a second {err.name}, without a new checkpoint "
            "(the last one written is kept: --restart continues from it).",
            file=sys.stderr,
        )
        return exit_code(err.signum)
    except EarlyStop as err:
        print(f"mpmflow: stopped by {err.name} {early.when()}.", file=sys.stderr)
        return exit_code(err.signum)
    except KeyboardInterrupt:
        print(f"mpmflow: stopped by SIGINT {early.when()}.", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
