"""Chorin's projection in MPM (Kularathna & Soga 2017; one time step as in docs/method.md).

The step itself is compiled (``kernels.step``): this class owns its arrays, runs chunks of
steps, and turns a failure reported by the compiled code into a message.
"""

from dataclasses import dataclass

import numpy as np

from .. import materials, obstacles, pressure, volume_correction
from ..errors import SolverError
from ..kernels import step, viscous, walls
from ..linsolve import SMOOTHING_SWEEPS
from ..transfers import flip_per_step
from . import register

MARGIN = 1e-6  # particles put back inside stay this fraction of a cell off the wall
SURFACE = {"gauss": step.GAUSS, "divergence": step.DIVERGENCE, "consistent": step.CONSISTENT}


@dataclass
class StepReport:
    """What a scheme reports after one or more steps."""

    unknowns: int = 0  # the largest count of pressure unknowns in a step
    solves: int = 0
    iterations: int = 0
    max_iterations: int = 0  # the most iterations in one step
    residual: float = 0.0  # the worst relative residual
    released: int = 0
    moved_inside: int = 0
    viscous_iterations: int = 0  # of the viscous solves (viscous materials)

    def merge(self, other):
        return StepReport(max(self.unknowns, other.unknowns), self.solves + other.solves,
                          self.iterations + other.iterations,
                          max(self.max_iterations, other.max_iterations),
                          max(self.residual, other.residual), self.released + other.released,
                          self.moved_inside + other.moved_inside,
                          self.viscous_iterations + other.viscous_iterations)

    @classmethod
    def of(cls, report):
        """From the compiled step's ``report`` array."""
        return cls(int(report[step.R_UNKNOWNS]), int(report[step.R_SOLVES]),
                   int(report[step.R_ITERATIONS]), int(report[step.R_MAX_ITERATIONS]),
                   float(report[step.R_RESIDUAL]), int(report[step.R_RELEASED]),
                   int(report[step.R_MOVED]), int(report[step.R_VISCOUS_ITERATIONS]))


def work_arrays(grid, count, volume_correction_on, viscous_on):
    """The step's arrays (``kernels.step.Work``), allocated once."""
    D, nn, nc = grid.dim, grid.nnodes, grid.ncells
    nvc, nvn = (nc, nn) if viscous_on else (0, 0)  # the viscous predictor's, when it runs
    NS = 3**D
    nv = nc if volume_correction_on else 0  # the correction's arrays, when it runs
    faces = []
    for k in range(D):
        shape = list(grid.cells)
        shape[k] += 1
        faces.append(np.zeros(int(np.prod(shape)) if volume_correction_on else 0))
    return step.Work(
        cell=np.empty(count, dtype=np.int64), start=np.empty(nc + 1, dtype=np.int64),
        order=np.empty(count, dtype=np.int64), theta=np.zeros(nc),
        node_mass=np.zeros(nn), node_mom=np.zeros((nn, D)), node_vol=np.zeros(nn),
        v_old=np.zeros((nn, D)), v_star=np.zeros((nn, D)), v_c=np.zeros((nn, D)),
        v_new=np.zeros((nn, D)), node_f=np.zeros(nn), enclosed=np.zeros(nc, dtype=np.bool_),
        slot=np.empty(nc, dtype=np.int64), surface_slot=np.empty(nc, dtype=np.int64),
        node_row=np.full(nn, -1, dtype=np.int64), contact=np.zeros((nn, D), dtype=np.bool_),
        ocontact=np.zeros(nn, dtype=np.bool_), p_node=np.zeros(nn),
        cell_vol=np.zeros(nv), density=np.zeros(nv), cell_row=np.empty(nv, dtype=np.int64),
        vol_cols=np.empty((nv, NS), dtype=np.int64), vol_vals=np.empty((nv, NS)),
        vol_rhs=np.empty(nv), vol_rows=np.empty(nv, dtype=np.int64), q=np.zeros(nv),
        faces=tuple(faces), no_faces=tuple(np.zeros(0) for _ in range(D)),
        eta=np.zeros(nvc), eta_weight=np.zeros(nvc), vrow=np.empty((nvn, D), dtype=np.int64),
        vu=np.zeros((nvn, D)), voff=np.zeros(D + 1, dtype=np.int64))


@register("projection")
class ProjectionScheme:
    def __init__(self, case, grid, particles):
        s = case.solver
        self.case = case
        self.grid = grid
        self.particles = particles
        node, axis, sign = walls.wall_pairs(tuple(grid.cells))
        self.solids = obstacles.of_case(case, grid)
        o = self.solids
        self.viscous = materials.is_viscous(case.material)
        cells = tuple(int(c) for c in grid.cells)
        T = (viscous.gauss_gradients(cells, float(grid.spacing)) if self.viscous
             else np.zeros((0, 0, 0, 0)))
        self.G = step.Grid(float(grid.spacing), cells,
                           float(grid.cell_volume), np.asarray(grid.size, dtype=float),
                           MARGIN * grid.spacing, node, axis, sign, o.phi, o.open,
                           o.static_slot, o.K, o.C, o.V, o.F, o.Wf, o.node, o.normal,
                           o.no_slip, T)
        self.W = work_arrays(grid, particles.count, s.volume_correction > 0, self.viscous)
        step.launch_threads()
        self.compiled_advance = step.advance
        self.python_pressure = (None if s.linear_solver == "multigrid"
                                else pressure.PythonPressure(grid, s))
        self.steps = 0  # steps taken: the volume correction runs on every n-th (n from dt)
        self.last_unknowns = 0

    @property
    def p_node(self):
        """The nodal pressure of the last step (Pa)."""
        return self.W.p_node

    def options(self, dt):
        """The compiled step's settings for steps of dt (``kernels.step.Options``)."""
        s, m = self.case.solver, self.case.material
        every = (max(1, round(s.volume_correction_interval / dt))
                 if s.volume_correction > 0 else 0)
        particles = s.partial_cell_quadrature == "particles"
        model, params = materials.parameters(m)
        return step.Options(
            dt=float(dt), gravity=np.asarray(self.case.physics.gravity, dtype=float),
            rho=float(m.density), flip=float(flip_per_step(s.flip, dt)),
            full=float(s.full_cell_threshold), sparse=float(s.sparse_cell_threshold),
            partial_particles=particles,
            surface=step.GAUSS if particles else SURFACE[s.surface_quadrature],
            subcell=s.free_surface == "subcell", wall_flux=bool(s.wall_flux),
            no_slip=self.case.domain.walls == "no_slip", theta_min=float(s.ghost_theta_min),
            expansion=float(s.density_correction), tol=float(s.tolerance),
            max_iterations=int(s.max_iterations), sweeps=SMOOTHING_SWEEPS,
            volume_rate=float(s.volume_correction), volume_every=int(every),
            volume_tol=volume_correction.TOLERANCE,
            volume_max_iterations=volume_correction.MAX_ITERATIONS,
            volume_dmax=volume_correction.MAX_DISPLACEMENT, viscous=self.viscous,
            model=int(model), model_params=params)

    def state(self):
        """What the scheme carries from one step to the next beyond the particles: the nodal
        pressure and the volume correction's last solution (the warm starts of the next
        solves). Everything else is rebuilt each step."""
        state = {"p_node": self.W.p_node.copy(),
                 "last_unknowns": np.array(self.last_unknowns), "steps": np.array(self.steps)}
        if self.W.q.size:
            state["volume_q"] = self.W.q.copy()
        return state

    def restore(self, state):
        """Continue from ``state()`` (a checkpoint)."""
        np.copyto(self.W.p_node, state["p_node"])
        self.last_unknowns = int(state["last_unknowns"])
        self.steps = int(state["steps"])
        if self.W.q.size:
            np.copyto(self.W.q, state["volume_q"])

    def check_free_surface(self):
        """Raise SolverError ("singular") when the material as placed touches no free
        surface: the first step's classification and assembly, without the solve (its
        buffers are overwritten by the step). Lets a run refuse such a case before it
        starts instead of failing at step 1."""
        P = self.particles
        Pt = step.Particles(P.x, P.v, P.mass, P.volume, P.pressure)
        O = self.options(1.0)  # the step size does not change which nodes are unknowns
        integrals, rows = step.predict(Pt, self.G, O, self.W, False)
        if rows.size and not step.pressure_matrix(self.G, O, self.W, integrals, rows)[2]:
            raise pressure.singular(" at the start")

    def advance(self, dt, nsteps, where=""):
        """``nsteps`` steps of size dt; ``where(k)`` names step k in messages. The report sums
        the steps (residual: the worst)."""
        P = self.particles
        if self.W.cell.shape[0] != P.count:
            self.W = self.W._replace(cell=np.empty(P.count, dtype=np.int64),
                                     order=np.empty(P.count, dtype=np.int64))
        Pt = step.Particles(P.x, P.v, P.mass, P.volume, P.pressure)
        O = self.options(dt)
        report = np.zeros(step.REPORT_SIZE)
        try:
            if self.python_pressure is None:
                done = self.compiled_advance(Pt, self.G, O, self.W, self.steps + 1, nsteps,
                                             report)
            else:
                done = self._python_steps(Pt, O, nsteps, report, where)
        except pressure.SETUP_ERRORS as err:
            k = int(report[step.R_STEP])
            self.steps += k
            raise pressure.setup_failed(where(k), err, int(report[step.R_LAST_UNKNOWNS]))
        self.steps += done
        self.last_unknowns = int(report[step.R_LAST_UNKNOWNS])
        if done < nsteps:
            self._fail(report, where(done))
        return StepReport.of(report)

    def _python_steps(self, Pt, O, nsteps, report, where):
        """The steps with the pressure solved in Python (``pressure.PythonPressure``)."""
        for k in range(nsteps):
            report[step.R_STEP] = k
            correct = O.volume_every > 0 and (self.steps + k + 1) % O.volume_every == 0
            integrals, rows = step.predict(Pt, self.G, O, self.W, correct)
            report[step.R_UNKNOWNS] = max(report[step.R_UNKNOWNS], rows.size)
            report[step.R_LAST_UNKNOWNS] = rows.size
            status = step.viscous_predictor(self.G, O, self.W, integrals, report)
            if status != step.OK:
                report[step.R_STATUS] = status
                return k
            self.python_pressure.solve(self.G, O, self.W, integrals, rows, report, where(k))
            status = step.finish(Pt, self.G, O, self.W, integrals, correct, report)
            if status != step.OK:
                report[step.R_STATUS] = status
                return k
        return nsteps

    def _fail(self, report, where):
        status = int(report[step.R_STATUS])
        n = int(report[step.R_FAIL_SIZE])
        iterations = int(report[step.R_FAIL_ITERATIONS])
        residual = float(report[step.R_FAIL_RESIDUAL])
        worst = int(report[step.R_FAIL_NODE])
        if status == step.SINGULAR:
            raise pressure.singular(where)
        if status == step.PRESSURE_NOT_CONVERGED:
            raise pressure.not_converged(where, residual, iterations, self.case.solver, n,
                                         self.grid.node_coordinates()[worst])
        if status == step.VOLUME_NOT_CONVERGED:
            raise volume_correction.not_converged(where, residual, iterations, n)
        if status == step.VISCOUS_NOT_CONVERGED:
            m = self.case.material
            raise SolverError(
                f"The viscous solve did not converge{where}: relative residual "
                f"{residual:.3e} after {iterations} iterations (solver.tolerance = "
                f"{self.case.solver.tolerance:g}, solver.max_iterations = "
                f"{self.case.solver.max_iterations}); {n} unknowns (velocity components), "
                "largest residual at node ("
                + ", ".join(f"{c:.4g}" for c in self.grid.node_coordinates()[worst])
                + ") m. "
                f"Try a smaller time.dt, a larger solver.max_iterations"
                + (", or a smaller material.max_viscosity" if m.model in
                   ("herschel_bulkley", "mu_i") else "") + ".")
        raise SolverError(f"The step failed{where} with status {status}.")
