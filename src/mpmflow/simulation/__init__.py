"""A run of a case: ``Simulation``, and the schedules its writers and callbacks act on.

    sim = Simulation(case, out_dir)
    sim.add_callback(func, IterationInterval(10))  # func(sim), may call sim.stop(why)
    sim.add_writer(writer, TimeInterval(0.05))      # writer(sim)
    summary = sim.run()

Modules: ``loop`` (Simulation: the time loop and its public API), ``schedules``,
``writers`` (time series, probes, snapshots), ``checkpointer`` (the checkpoint writer and
resuming), ``callbacks`` (blow-up guard, progress, thread governor, signals, wall budget),
``setup`` (building and checking what a run is made of), ``summary`` (summary.json).
"""

from .counters import Counters
from .loop import Simulation
from .schedules import IterationInterval, Schedule, TimeInterval, WallTimeInterval

__all__ = [
    "Simulation",
    "Counters",
    "Schedule",
    "TimeInterval",
    "IterationInterval",
    "WallTimeInterval",
]
