"""The scheme's state and the one door to the compiled core (``mpmflow._core``).

Nothing else in mpmflow imports the core: the rest of the package calls the functions
here, which take NumPy arrays and grids and call the C++ kernels (src/core, one header/
source pair per concept). The core is built once, at install (scikit-build-core, CMake);
nothing compiles at run time. One module per concern of the core (pressure, transfer,
step, viscous, explicit); every name is importable from ``mpmflow.state``.
"""

try:
    from .. import _core
except ImportError as err:  # a source tree without the install's build
    raise ImportError(
        f"mpmflow's compiled core (mpmflow._core) could not be loaded ({err}). It is built "
        "when the package is installed: run `make setup`, or `pip install -e .` in the "
        "repository (needs a C++17 compiler with OpenMP and CMake >= 3.18)."
    ) from err

CHUNKS: int = _core.CHUNKS
# a cell at least this full is half full (src/core/volume_correction.hpp)
HALF_FULL: float = _core.HALF_FULL
POOL: int = _core.max_threads()  # the threads at import: OMP_NUM_THREADS, or the cores


def max_threads() -> int:
    """The threads the core's parallel loops use."""
    return int(_core.max_threads())


def set_threads(n: int) -> None:
    """Run the core's parallel loops on n threads."""
    _core.set_threads(int(n))


# every kernel wrapper, as state.<name>
from .explicit import (  # noqa: E402 (the core is loaded first, with its message)
    ExplicitSettings,
    ExplicitWork,
    explicit_cell_state,
    explicit_max_speed,
    explicit_particle_state,
    explicit_steps,
)
from .pressure import (  # noqa: E402 (the core is loaded first, with its message)
    COARSEST,
    PARALLEL_ROWS,
    Multigrid,
    apply_walls,
    dot,
    gauss_cell_tensors,
    matvec,
    multigrid,
    particle_cell_tensors,
    reach,
    release_contact,
    residual,
    start_contact,
    wall_pairs,
    worst_row,
)
from .step import (  # noqa: E402 (the core is loaded first, with its message)
    OK,
    PHASES,
    SURFACE_QUADRATURE,
    CoreOptions,
    CoreReport,
    CoreState,
    Report,
    Status,
    adaptive_dt,
    step_options,
    step_state,
    volume_due_adaptive,
    volume_due_fixed,
)
from .transfer import (  # noqa: E402 (the core is loaded first, with its message)
    SLIVER,
    Totals,
    assemble_volume,
    cell_index,
    cell_volume,
    cell_volume_fraction,
    correct_velocity,
    counting_sort,
    cut_cell_tensors,
    extend_velocity,
    face_displacements,
    face_mass,
    flip_per_step,
    grid_to_particles,
    particle_totals,
    particles_to_grid,
    pressure_noise,
    push_out,
    sliver_fractions,
    strips,
)
from .viscous import (  # noqa: E402 (the core is loaded first, with its message)
    DRUCKER_PRAGER,
    ELASTIC,
    HERSCHEL_BULKLEY,
    MU_I,
    NEWTONIAN,
    POROELASTIC,
    VON_MISES,
    WATER,
    cell_viscosity,
    gauss_gradients,
    number_unknowns,
    update_stress,
    viscosity,
    viscous_assemble,
    viscous_solve,
    viscous_worst_row,
)

__all__ = [
    "CHUNKS",
    "COARSEST",
    "CoreOptions",
    "CoreReport",
    "CoreState",
    "ExplicitSettings",
    "ExplicitWork",
    "DRUCKER_PRAGER",
    "POROELASTIC",
    "ELASTIC",
    "HERSCHEL_BULKLEY",
    "MU_I",
    "Multigrid",
    "NEWTONIAN",
    "OK",
    "PARALLEL_ROWS",
    "PHASES",
    "POOL",
    "Report",
    "SLIVER",
    "SURFACE_QUADRATURE",
    "Totals",
    "Status",
    "VON_MISES",
    "WATER",
    "apply_walls",
    "assemble_volume",
    "cell_index",
    "cell_viscosity",
    "cell_volume",
    "cell_volume_fraction",
    "correct_velocity",
    "counting_sort",
    "cut_cell_tensors",
    "dot",
    "explicit_cell_state",
    "explicit_max_speed",
    "explicit_particle_state",
    "explicit_steps",
    "extend_velocity",
    "face_displacements",
    "face_mass",
    "flip_per_step",
    "gauss_cell_tensors",
    "gauss_gradients",
    "grid_to_particles",
    "matvec",
    "max_threads",
    "multigrid",
    "number_unknowns",
    "particle_cell_tensors",
    "particle_totals",
    "particles_to_grid",
    "pressure_noise",
    "push_out",
    "reach",
    "release_contact",
    "residual",
    "set_threads",
    "sliver_fractions",
    "start_contact",
    "step_options",
    "step_state",
    "adaptive_dt",
    "volume_due_adaptive",
    "volume_due_fixed",
    "strips",
    "update_stress",
    "viscosity",
    "viscous_assemble",
    "viscous_solve",
    "viscous_worst_row",
    "wall_pairs",
    "worst_row",
]
