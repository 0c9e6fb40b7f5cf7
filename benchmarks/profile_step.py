"""Where the time of a step goes: the dam break profiled phase by phase.

Runs a case in-process under cProfile (after a short warm-up run that loads Numba's
cache) and sums the time of each compiled kernel and of the Python around it into the
phases of a step. Prints a Markdown table of milliseconds per step.

    python benchmarks/profile_step.py [--case examples/dam_break.toml] [--set key=value ...] [--cpu]

cProfile adds a few microseconds per Python call, so the "Python glue" row is an upper
bound; the kernels' own times are not affected (each is one call).
"""

import argparse
import cProfile
import pstats
import time
from pathlib import Path

import numba

ROOT = Path(__file__).resolve().parents[1]

# function name -> phase; anything else counts as Python glue (keep_inside, nodal_velocity
# and wall_contact are names of earlier versions, so that their profiles compare)
PHASES = {
    "transfers (P2G, G2P, binning, walls)": (
        "particles_to_grid", "grid_to_particles", "cell_index", "counting_sort",
        "cell_volume_fraction", "bin_particles", "keep_inside", "nodal_velocity"),
    "quadrature and assembly": (
        "particle_cell_tensors", "gauss_cell_tensors", "assemble_matrix", "assemble_rhs",
        "integrals"),
    "free surface": ("nodal_fraction", "enclosed_cells", "classify_nodes", "ghost_pressures"),
    "pressure solve (multigrid set-up)": ("build_hierarchy",),
    "pressure solve (PCG iterations)": ("pcg",),
    "corrector and walls": ("correct_velocity", "apply_walls", "start_contact",
                            "release_contact"),
    "volume correction (system, solve, displacements)": (
        "faces", "assemble_2d", "face_displacements"),
    "outputs (diagnostics, files)": (
        "_output", "measure", "pressure_noise", "write", "append", "front_and_height"),
}


def phase_of(name):
    for phase, names in PHASES.items():
        if any(name.startswith(n) for n in names):
            return phase
    return None


def profile(case_path, overrides, cpu=False):
    from mpmflow import Simulation, load_case

    warm = load_case(case_path, [*overrides, "time.end=0.003", "output.interval=0.001"])
    Simulation(warm).run()
    case = load_case(case_path, overrides)
    sim = Simulation(case)
    clock = time.process_time if cpu else time.perf_counter
    prof = cProfile.Profile(clock)
    t0 = clock()
    prof.enable()
    sim.run()
    prof.disable()
    wall = clock() - t0
    stats = pstats.Stats(prof).stats
    # a phase's time: the inclusive time of its functions, over the calls that come from
    # outside every phase (calls from within a phase are in that caller's time already)
    totals = dict.fromkeys(PHASES, 0.0)
    for (_, _, name), (_, _, _, _, callers) in stats.items():
        phase = phase_of(name)
        if phase is None:
            continue
        for caller, (_, _, _, cumtime) in callers.items():
            if phase_of(caller[2]) is None:
                totals[phase] += cumtime
    steps = sim.steps
    glue = wall - sum(totals.values())
    return sim, wall, steps, totals, glue


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default=str(ROOT / "examples" / "dam_break.toml"))
    ap.add_argument("--set", action="append", default=[], dest="overrides")
    ap.add_argument("--cpu", action="store_true",
                    help="CPU time of the process instead of wall time (steadier on a busy "
                         "machine; use with NUMBA_NUM_THREADS=1)")
    args = ap.parse_args()
    sim, wall, steps, totals, glue = profile(args.case, args.overrides, args.cpu)
    print(f"{Path(args.case).name} {' '.join(args.overrides)}: {sim.particles.count} "
          f"particles, {steps} steps, time loop {wall:.2f} s ({'CPU' if args.cpu else 'wall'}) "
          f"under cProfile, {numba.get_num_threads()} threads")
    print()
    print("| phase | ms per step | share |")
    print("|---|---|---|")
    for phase, t in [*totals.items(), ("Python glue (the rest)", glue)]:
        print(f"| {phase} | {1e3 * t / steps:.3f} | {100 * t / wall:.0f}% |")
    print(f"| total | {1e3 * wall / steps:.3f} | 100% |")


if __name__ == "__main__":
    main()
