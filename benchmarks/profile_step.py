"""Where the time of a step goes: the dam break timed phase by phase.

The step is one compiled call (``mpmflow.kernels.step``), which no Python profiler sees
into. This script runs the case twice in-process (after a short warm-up that loads Numba's
cache): once as it runs for users, and once with the compiled ``advance`` replaced by a
Python loop that calls the same compiled phases one by one with a timer around each. The
replay must give bit-identical particles (checked and printed); the difference between the
two wall times is the cost of returning to Python between the phases.

    python benchmarks/profile_step.py [--case examples/dam_break.toml] [--set key=value ...]

Prints a Markdown table of milliseconds per step.
"""

import argparse
import time
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parents[1]

PHASES = ("binning", "particle to grid", "free surface (node fractions, classify)",
          "cell integrals (quadrature)", "pressure (assembly, multigrid, PCG, walls)",
          "corrector and walls", "volume correction", "grid to particle")


def timed_advance(totals):
    """A drop-in for the compiled ``advance`` that times each phase into ``totals``."""
    from mpmflow.kernels import corrector, cutcells, step, walls
    from mpmflow.kernels.transfer import grid_to_particles as g2p
    from mpmflow.kernels.transfer import particles_to_grid as p2g

    clock = time.perf_counter

    def advance(P, G, O, W, first, nsteps, report):
        for k in range(nsteps):
            report[step.R_STEP] = k
            correct = O.volume_every > 0 and (first + k) % O.volume_every == 0
            t0 = clock()
            step.bin_particles(P, G, W)
            t1 = clock()
            p2g(P.x, P.v, P.mass, P.volume, W.order, W.start, G.h, G.cells, O.gravity, O.dt,
                W.node_mass, W.node_mom, W.node_vol, W.v_old, W.v_star,
                W.cell_vol if correct else W.cell_vol[:0])
            if G.phi.shape[0] > 0:
                cutcells.extend_velocity(G.onode, G.cells, W.node_mass, W.v_old, W.v_star)
            t2 = clock()
            step.node_fractions(G, O, W)
            t3 = clock()
            integrals = step.cell_integrals(P, G, O, W)
            t4 = clock()
            rows = step.classify_nodes(G, O, W, integrals[0])
            t5 = clock()
            report[step.R_UNKNOWNS] = max(report[step.R_UNKNOWNS], rows.shape[0])
            report[step.R_LAST_UNKNOWNS] = rows.shape[0]
            status = step.pressure_multigrid(G, O, W, integrals, rows, report)
            t6 = clock()
            if status != step.OK:
                report[step.R_STATUS] = status
                return k
            corrector.correct_velocity(G.cells, integrals[5], integrals[6], integrals[7],
                                       W.p_node, W.v_star, O.dt / O.rho, W.v_new)
            walls.apply_walls(G.wall_node, G.wall_axis, G.wall_sign, W.v_new, W.contact,
                              O.no_slip)
            walls.apply_obstacles(G.onode, G.onormal, G.ono_slip, W.v_new, W.ocontact)
            t7 = clock()
            faces = W.no_faces
            if correct:
                status = step.volume_correction(G, O, W, report)
                if status != step.OK:
                    report[step.R_STATUS] = status
                    return k
                faces = W.faces
            t8 = clock()
            report[step.R_MOVED] += g2p(P.x, P.v, P.pressure, G.h, G.cells, W.v_old, W.v_new,
                                        W.p_node, O.dt, O.flip, G.upper, G.margin, faces)
            if G.phi.shape[0] > 0:
                report[step.R_MOVED] += cutcells.push_out(P.x, P.v, G.phi, G.h, G.cells,
                                                          G.margin)
            t9 = clock()
            for name, dt in zip(PHASES, (t1 - t0, t2 - t1, (t3 - t2) + (t5 - t4), t4 - t3,
                                         t6 - t5, t7 - t6, t8 - t7, t9 - t8)):
                totals[name] += dt
        return nsteps

    return advance


def run(case_path, overrides, replay):
    from mpmflow import Simulation, load_case

    sim = Simulation(load_case(case_path, overrides))
    totals = dict.fromkeys(PHASES, 0.0)
    if replay:
        sim.scheme.compiled_advance = timed_advance(totals)
    t0 = time.perf_counter()
    sim.run()
    return sim, time.perf_counter() - t0, totals


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default=str(ROOT / "examples" / "dam_break.toml"))
    ap.add_argument("--set", action="append", default=[], dest="overrides")
    args = ap.parse_args()
    from mpmflow import Simulation, load_case

    Simulation(load_case(args.case, [*args.overrides, "time.end=0.003",
                                     "output.interval=0.001"])).run()
    fused, wall_fused, _ = run(args.case, args.overrides, replay=False)
    replayed, wall, totals = run(args.case, args.overrides, replay=True)
    same = (np.array_equal(fused.particles.x, replayed.particles.x)
            and np.array_equal(fused.particles.v, replayed.particles.v))
    steps = replayed.steps
    print(f"{Path(args.case).name} {' '.join(args.overrides)}: {replayed.particles.count} "
          f"particles, {steps} steps, {numba.get_num_threads()} threads; the time loop takes "
          f"{wall_fused:.2f} s fused, {wall:.2f} s replayed phase by phase (particles "
          f"{'bit-identical' if same else 'DIFFERENT'})")
    print()
    print("| phase | ms per step | share |")
    print("|---|---|---|")
    rest = wall - sum(totals.values())
    for phase, t in [*totals.items(), ("outputs and Python between the phases", rest)]:
        print(f"| {phase} | {1e3 * t / steps:.3f} | {100 * t / wall:.0f}% |")
    print(f"| total (replayed) | {1e3 * wall / steps:.3f} | 100% |")
    print(f"| total (fused, as users run it) | {1e3 * wall_fused / steps:.3f} | |")
    if not same:
        raise SystemExit("the replay differs from the fused step: update timed_advance")


if __name__ == "__main__":
    main()
