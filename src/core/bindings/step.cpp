// The projection scheme's State<D> as Python classes State2 and State3, with its Options
// and Report. The State keeps the grid's tables as views: the bound object holds the NumPy
// arrays alive for its life.
#include "../step.hpp"

#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <typeinfo>
#include <vector>

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

namespace {

// A NumPy view of the step's storage (rv_policy::reference: without an owner nanobind would
// hand Python a copy, and what Python writes into it would be lost); valid during a call.
template <class T, int R>
nb::object numpy_view(View<T, R> v) {
  std::array<std::size_t, R> shape{};
  for (int k = 0; k < R; ++k) shape[k] = static_cast<std::size_t>(v.extent(k));
  return nb::cast(nb::ndarray<nb::numpy, std::remove_const_t<T>>(
                      const_cast<std::remove_const_t<T>*>(v.data()), R, shape.data(), nb::handle()),
                  nb::rv_policy::reference);
}

// (iterations, relative residual) from Python
SolveResult solve_result(nb::object out) {
  SolveResult r;
  r.iterations = nb::cast<index_t>(out[0]);
  r.residual = nb::cast<double>(out[1]);
  return r;
}

// A solver from Python for one of the step's ELL systems (State.use_solvers: the pressure's,
// amg or direct, or a rank's over the ranks; the volume correction's, a rank's): its
// setup(cols, vals, rows) and solve(rhs, x) -> (iterations, residual), called with the GIL
// (the step runs without it). The arrays are views of the step's storage, valid during the
// call only (a solver keeps copies); solve writes its solution into x, which holds the
// initial guess.
class PythonLinear : public LinearSolver {
 public:
  explicit PythonLinear(nb::object solver) : solver_(std::move(solver)) {}
  ~PythonLinear() override {
    nb::gil_scoped_acquire acquire;
    solver_.reset();
  }
  void setup(View<const index_t, 2> cols, View<const double, 2> vals,
             View<const index_t> rows) override {
    nb::gil_scoped_acquire acquire;
    solver_.attr("setup")(numpy_view(cols), numpy_view(vals), numpy_view(rows));
  }
  SolveResult solve(View<const double> rhs, View<double> x) override {
    nb::gil_scoped_acquire acquire;
    return solve_result(solver_.attr("solve")(numpy_view(rhs), numpy_view(x)));
  }

 private:
  nb::object solver_;
};

// The viscous predictor's solver from Python (a rank's): solve(x) -> (iterations, residual),
// the system read from the state's viscous_* arrays.
class PythonViscous : public ViscousSolver {
 public:
  explicit PythonViscous(nb::object solver) : solver_(std::move(solver)) {}
  ~PythonViscous() override {
    nb::gil_scoped_acquire acquire;
    solver_.reset();
  }
  SolveResult solve(View<double> x) override {
    nb::gil_scoped_acquire acquire;
    return solve_result(solver_.attr("solve")(numpy_view(x)));
  }

 private:
  nb::object solver_;
};

template <int D>
struct BoundState;

// Between two steps of a chunk (run without the GIL): Python's signal handlers run, so
// that a SIGINT or SIGTERM whose handler raises (the run's second signal: stop at once)
// stops the chunk after the step in progress, and the exception reaches the caller.
class SignalCheck {
 public:
  std::function<bool()> between() {
    return [this] {
      nb::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() == 0) return true;
      error_ = std::make_unique<nb::python_error>();
      return false;
    };
  }
  void raise_if_any() {
    if (error_) throw nb::python_error(*error_);
  }

 private:
  std::unique_ptr<nb::python_error> error_;
};

// chunk(between) without the GIL, with SignalCheck's between(); a handler's exception is
// raised once the chunk has stopped.
template <class F>
auto run_chunk(F&& chunk) {
  SignalCheck check;
  const auto between = check.between();
  decltype(chunk(between)) result;
  {
    nb::gil_scoped_release release;
    result = chunk(between);
  }
  check.raise_if_any();
  return result;
}

template <class T, int R>
View<const T, R> table(nb::object a, const char* name, std::vector<nb::object>& keep) {
  keep.push_back(a);
  // no conversion: a converted copy would die with this call and leave the view dangling
  try {
    return view<const T, R>(nb::cast<Array<const T>>(a, false), name);
  } catch (const std::bad_cast&) {
    throw std::invalid_argument(std::string("the step's table ") + name +
                                " must be a C-contiguous NumPy array of the core's type "
                                "(float64, int64 or bool): mpmflow.state.step_state makes one");
  }
}

template <class T, int R>
nb::ndarray<nb::numpy, T> out(View<T, R> v, nb::handle owner) {
  std::array<std::size_t, R> shape{};
  for (int k = 0; k < R; ++k) shape[k] = static_cast<std::size_t>(v.extent(k));
  return nb::ndarray<nb::numpy, T>(v.data(), R, shape.data(), owner);
}

// A read-only property: the state's array Get() as a NumPy view that keeps the bound state
// (and so the array) alive.
template <int D, auto Get>
auto state_view(nb::handle h) {
  return out((nb::cast<BoundState<D>&>(h).state.get()->*Get)(), h);
}

using Affine = std::optional<Array<double>>;

// The particles; affine (n x D x D): APIC's matrices, None: FLIP/PIC transfers; stress
// (n x D x D), plastic_strain and yielding (n): a solid's history (plasticity.hpp), None: a
// fluid (all three or none).
template <int D>
Particles<D> particles(Array<double> x, Array<double> v, Array<double> mass, Array<double> volume,
                       Array<double> pressure, const Affine& affine = std::nullopt,
                       const Affine& stress = std::nullopt,
                       const Affine& plastic_strain = std::nullopt,
                       const Affine& yielding = std::nullopt) {
  Particles<D> P{view<double, 2>(x, "x"), view<double, 2>(v, "v"), view<double>(mass, "mass"),
                 view<double>(volume, "volume"), view<double>(pressure)};
  const index_t n = P.x.extent(0);
  if (P.x.extent(1) != D || P.v.extent(0) != n || P.v.extent(1) != D || P.mass.size() != n ||
      P.volume.size() != n || P.pressure.size() != n)
    throw std::invalid_argument("particle arrays of inconsistent shapes");
  if (affine) {
    P.affine = view<double, 3>(*affine, "affine");
    if (P.affine.extent(0) != n || P.affine.extent(1) != D || P.affine.extent(2) != D)
      throw std::invalid_argument("affine: one D x D matrix per particle");
  }
  if (bool(stress) != bool(plastic_strain) || bool(stress) != bool(yielding))
    throw std::invalid_argument("stress, plastic_strain, yielding: give all three or none");
  if (stress) {
    P.stress = view<double, 3>(*stress, "stress");
    P.plastic_strain = view<double>(*plastic_strain, "plastic_strain");
    P.yielding = view<double>(*yielding, "yielding");
    if (P.stress.extent(0) != n || P.stress.extent(1) != D || P.stress.extent(2) != D ||
        P.plastic_strain.size() != n || P.yielding.size() != n)
      throw std::invalid_argument(
          "stress: one D x D matrix per particle; plastic_strain, "
          "yielding: one value per particle");
  }
  return P;
}

// A rank's exchange from Python (State.use_exchange; mpmflow.parallel's RankExchange,
// over MPI): each call of the seam (exchange.hpp) calls the method of the same name with
// the GIL. particles() returns (owned, x, v, mass, volume, pressure, affine, stress,
// plastic_strain, yielding; None where not carried), arrays
// the Python object keeps alive until its next call; fill_nodes and fill_cells get NumPy
// views of the step's arrays to overwrite in place.
template <int D>
class PythonExchange : public Exchange<D> {
 public:
  PythonExchange(nb::object exchange, nb::object owned_nodes, nb::object owned_cells)
      : exchange_(std::move(exchange)),
        nodes_(std::move(owned_nodes)),
        cells_(std::move(owned_cells)),
        owned_nodes_(view<const bool>(nb::cast<Array<const bool>>(nodes_, false), "owned_nodes")),
        owned_cells_(view<const bool>(nb::cast<Array<const bool>>(cells_, false), "owned_cells")) {}
  ~PythonExchange() override {
    nb::gil_scoped_acquire acquire;
    exchange_.reset();
    nodes_.reset();
    cells_.reset();
  }
  bool shared() const override { return true; }
  Particles<D> particles(const Particles<D>&) override {
    nb::gil_scoped_acquire acquire;
    nb::tuple t = nb::cast<nb::tuple>(exchange_.attr("particles")());
    if (t.size() != 10)
      throw std::invalid_argument(
          "exchange.particles() must return (owned, x, v, mass, volume, pressure, affine, "
          "stress, plastic_strain, yielding)");
    owned_ = nb::cast<index_t>(t[0]);
    auto arr = [&](int k) { return nb::cast<Array<double>>(t[k], false); };
    auto optional = [&](int k) { return t[k].is_none() ? Affine(std::nullopt) : Affine(arr(k)); };
    Particles<D> P = mpmflow::bind::particles<D>(
        arr(1), arr(2), arr(3), arr(4), arr(5), optional(6), optional(7), optional(8), optional(9));
    if (owned_ < 0 || owned_ > P.count())
      throw std::invalid_argument("exchange.particles(): owned out of range");
    return P;
  }
  index_t owned(const Particles<D>& P) override { return std::min(owned_, P.count()); }
  void fill_nodes(const View<double, 2>* fields, int count) override {
    fill("fill_nodes", fields, count);
  }
  void fill_cells(const View<double, 2>* fields, int count) override {
    fill("fill_cells", fields, count);
  }
  void own_unknowns(View<index_t> node_row) override {
    nb::gil_scoped_acquire acquire;
    exchange_.attr("own_unknowns")(numpy_view(node_row));
  }
  double max(double x) override {
    nb::gil_scoped_acquire acquire;
    return nb::cast<double>(exchange_.attr("max")(x));
  }
  index_t sum(index_t x) override {
    nb::gil_scoped_acquire acquire;
    return nb::cast<index_t>(exchange_.attr("sum")(x));
  }
  void sum_values(View<double> values) override {
    nb::gil_scoped_acquire acquire;
    exchange_.attr("sum_values")(numpy_view(values));
  }
  void refresh_halo() override {
    nb::gil_scoped_acquire acquire;
    exchange_.attr("refresh_halo")();
  }
  void migrate() override {
    nb::gil_scoped_acquire acquire;
    exchange_.attr("migrate")();
  }
  View<const bool> owned_nodes() override { return owned_nodes_; }
  View<const bool> owned_cells() override { return owned_cells_; }

 private:
  void fill(const char* name, const View<double, 2>* fields, int count) {
    nb::gil_scoped_acquire acquire;
    nb::list arrays;
    for (int k = 0; k < count; ++k) {
      const View<double, 2>& f = fields[k];
      if (f.extent(1) == 1)  // one value per row: a vector
        arrays.append(numpy_view(View<double>(f.data(), {f.extent(0)})));
      else
        arrays.append(numpy_view(f));
    }
    exchange_.attr(name)(*arrays);
  }
  nb::object exchange_, nodes_, cells_;
  View<const bool> owned_nodes_, owned_cells_;
  index_t owned_ = 0;
};

template <int D>
struct BoundState {
  std::vector<nb::object> keep;      // the arrays the tables view
  std::array<bool, 2 * D> outlet{};  // the outlet sides the tables view
  std::unique_ptr<PythonLinear> solver, volume_solver;
  std::unique_ptr<PythonViscous> viscous_solver;
  std::unique_ptr<PythonExchange<D>> exchange;
  std::unique_ptr<State<D>> state;
};

// the particle arguments: those a step writes must not be silently copied
#define MPMFLOW_PARTICLE_ARGS                                                      \
  nb::arg("x").noconvert(), nb::arg("v").noconvert(), nb::arg("mass").noconvert(), \
      nb::arg("volume").noconvert(), nb::arg("pressure").noconvert()
// the affine matrices (APIC), last, optional: None runs FLIP/PIC
// and a solid's history (stress, plastic_strain, yielding; None: a fluid)
#define MPMFLOW_AFFINE_ARG                                   \
  nb::arg("affine").noconvert().none() = nb::none(),         \
  nb::arg("stress").noconvert().none() = nb::none(),         \
  nb::arg("plastic_strain").noconvert().none() = nb::none(), \
  nb::arg("yielding").noconvert().none() = nb::none()

template <int D>
void bind_dim(nb::module_& m) {
  const std::string suffix = std::to_string(D);
  using S = BoundState<D>;
  using O = Options<D>;
  nb::class_<O>(m, ("Options" + suffix).c_str())
      .def(nb::init<>())
      .def_rw("dt", &O::dt)
      .def_rw("gravity", &O::gravity)
      .def_rw("rho", &O::rho)
      .def_rw("flip", &O::flip)
      .def_rw("full", &O::full)
      .def_rw("sparse", &O::sparse)
      .def_rw("partial_particles", &O::partial_particles)
      .def_rw("cell_pressure", &O::cell_pressure)
      .def_rw("coupled", &O::coupled)
      .def_rw("surface", &O::surface)
      .def_rw("subcell", &O::subcell)
      .def_rw("wall_flux", &O::wall_flux)
      .def_rw("pockets", &O::pockets)
      .def_rw("theta_min", &O::theta_min)
      .def_rw("shallow", &O::shallow)
      .def_rw("shallow_max_dt", &O::shallow_max_dt)
      .def_rw("expansion", &O::expansion)
      .def_rw("tol", &O::tol)
      .def_rw("max_iterations", &O::max_iterations)
      .def_rw("sweeps", &O::sweeps)
      .def_rw("volume_rate", &O::volume_rate)
      .def_rw("volume_every", &O::volume_every)
      .def_rw("volume_tol", &O::volume_tol)
      .def_rw("volume_max_iterations", &O::volume_max_iterations)
      .def_rw("volume_dmax", &O::volume_dmax)
      .def_rw("viscous", &O::viscous)
      .def_rw("model", &O::model)
      .def_rw("model_params", &O::model_params)
      .def_rw("courant", &O::courant)
      .def_rw("dt_max", &O::dt_max)
      .def_rw("flip_rate", &O::flip_rate)
      .def_rw("volume_interval", &O::volume_interval);

  nb::class_<S>(m, ("State" + suffix).c_str())
      .def(
          "__init__",
          [](S* self, double h, std::vector<index_t> cells, double cell_volume,
             std::array<double, D> lower, std::array<double, D> upper, double margin,
             nb::object wall_node, nb::object wall_axis, nb::object wall_sign,
             nb::object wall_no_slip, nb::object phi, nb::object open, nb::object static_slot,
             nb::object K, nb::object C, nb::object V, nb::object F, nb::object Wf,
             nb::object onode, nb::object onormal, nb::object ono_slip, nb::object viscous_T,
             bool volume_correction, bool viscous, std::vector<bool> periodic,
             std::vector<bool> outlet, nb::object wall_bonded, nb::object wall_velocity,
             nb::object inlet_axis, nb::object inlet_direction, nb::object inlet_speed,
             nb::object inlet_first, nb::object inlet_layer, nb::object inlet_spacing,
             nb::object inlet_mass, nb::object inlet_volume, nb::object damping, nb::object load) {
            new (self) S();
            auto& keep = self->keep;
            GridTables<D> T;
            T.wall_node = table<index_t, 1>(wall_node, "wall_node", keep);
            T.wall_axis = table<index_t, 1>(wall_axis, "wall_axis", keep);
            T.wall_sign = table<double, 1>(wall_sign, "wall_sign", keep);
            T.wall_no_slip = table<bool, 1>(wall_no_slip, "wall_no_slip", keep);
            if (T.wall_no_slip.size() != T.wall_node.size())
              throw std::invalid_argument("State: wall_no_slip needs one flag per wall pair");
            T.wall_bonded = table<bool, 1>(wall_bonded, "wall_bonded", keep);
            if (T.wall_bonded.size() > 0) {  // empty: none
              if (T.wall_bonded.size() != T.wall_node.size())
                throw std::invalid_argument("State: wall_bonded needs one flag per wall pair");
            }
            T.phi = table<double, 1>(phi, "phi", keep);
            T.open = table<double, 1>(open, "open", keep);
            T.static_slot = table<index_t, 1>(static_slot, "static_slot", keep);
            T.K_static = table<double, 3>(K, "K", keep);
            T.C_static = table<double, 4>(C, "C", keep);
            T.V_static = table<double, 2>(V, "V", keep);
            T.F_static = table<double, 4>(F, "F", keep);
            T.Wf_static = table<double, 4>(Wf, "Wf", keep);
            T.onode = table<index_t, 1>(onode, "onode", keep);
            T.onormal = table<double, 2>(onormal, "onormal", keep);
            T.ono_slip = table<bool, 1>(ono_slip, "ono_slip", keep);
            T.viscous_T = table<double, 4>(viscous_T, "viscous_T", keep);
            if (!outlet.empty() && outlet.size() != 2 * D)
              throw std::invalid_argument("State: outlet needs one flag per side");
            for (std::size_t s = 0; s < outlet.size(); ++s) self->outlet[s] = outlet[s];
            if (!outlet.empty()) T.outlet = View<const bool>(self->outlet.data(), {2 * D});
            const index_t nn = make_grid<D>(h, cells, periodic).nnodes;
            T.damping = table<double, 1>(damping, "damping", keep);
            if (T.damping.size() > 0 && T.damping.size() != nn)
              throw std::invalid_argument("State: damping needs one rate per node (or none)");
            T.load = table<double, 2>(load, "load", keep);
            if (T.load.size() > 0 && (T.load.extent(0) != nn || T.load.extent(1) != D))
              throw std::invalid_argument("State: load needs nnodes x D forces (or none)");
            T.wall_velocity = table<double, 2>(wall_velocity, "wall_velocity", keep);
            if (T.wall_velocity.size() > 0 &&
                (T.wall_velocity.extent(0) != nn || T.wall_velocity.extent(1) != D))
              throw std::invalid_argument("State: wall_velocity needs nnodes x D values (or none)");
            Inlets<D>& in = T.inlets;
            in.axis = table<index_t, 1>(inlet_axis, "inlet_axis", keep);
            in.direction = table<double, 1>(inlet_direction, "inlet_direction", keep);
            in.speed = table<double, 1>(inlet_speed, "inlet_speed", keep);
            in.first = table<index_t, 1>(inlet_first, "inlet_first", keep);
            in.layer = table<double, 2>(inlet_layer, "inlet_layer", keep);
            in.spacing = table<double, 1>(inlet_spacing, "inlet_spacing", keep);
            in.mass = table<double, 1>(inlet_mass, "inlet_mass", keep);
            in.volume = table<double, 1>(inlet_volume, "inlet_volume", keep);
            const index_t ninlets = in.direction.size();
            if (in.axis.size() != ninlets || in.spacing.size() != ninlets ||
                in.mass.size() != ninlets || in.volume.size() != ninlets ||
                (ninlets > 0 && in.first.size() != ninlets + 1) ||
                in.speed.size() != in.layer.extent(0))
              throw std::invalid_argument(
                  "State: the inlets need an axis, direction, spacing, mass and volume each, "
                  "inlets + 1 layer offsets and a speed per layer row");
            if (ninlets > 0) {
              if (in.layer.extent(1) != D || in.first(ninlets) != in.layer.extent(0))
                throw std::invalid_argument(
                    "State: inlet_layer needs rows x D positions, "
                    "inlet_first's last entry its rows");
              for (index_t q = 0; q < ninlets; ++q)
                if (in.axis(q) < 0 || in.axis(q) >= D || !(in.spacing(q) > 0.0) ||
                    !(in.mass(q) > 0.0) || !(in.volume(q) > 0.0) || in.first(q) > in.first(q + 1))
                  throw std::invalid_argument("State: inlet " + std::to_string(q) +
                                              " has an axis, particle or layer range out of range");
              for (index_t r = 0; r < in.speed.size(); ++r)
                if (!(in.speed(r) >= 0.0))
                  throw std::invalid_argument("State: an inlet row's speed must be >= 0");
            }
            self->state =
                std::make_unique<State<D>>(make_grid<D>(h, cells, periodic), cell_volume, lower,
                                           upper, margin, T, volume_correction, viscous);
          },
          "Build the step's state for a grid (spacing h, cell counts, periodic axes), the "
          "domain's corners (lower, upper: where particles are put back inside) and its tables.")
      .def(
          "use_solvers",
          [](S& self, nb::object pressure, nb::object volume, nb::object viscous) {
            self.state->use_solvers(nullptr);
            self.solver.reset();
            self.volume_solver.reset();
            self.viscous_solver.reset();
            if (!pressure.is_none()) self.solver = std::make_unique<PythonLinear>(pressure);
            if (!volume.is_none()) self.volume_solver = std::make_unique<PythonLinear>(volume);
            if (!viscous.is_none()) self.viscous_solver = std::make_unique<PythonViscous>(viscous);
            self.state->use_solvers(self.solver.get(), self.volume_solver.get(),
                                    self.viscous_solver.get());
          },
          nb::arg("pressure").none() = nb::none(), nb::arg("volume").none() = nb::none(),
          nb::arg("viscous").none() = nb::none(),
          "The systems' solvers from Python (None: the step's own multigrid): pressure and "
          "volume with setup(cols, vals, rows) for each matrix and solve(rhs, x) -> "
          "(iterations, true relative residual) for each right-hand side, the solution "
          "written into x (the initial guess); viscous with solve(x) -> (iterations, "
          "residual) on the last viscous_system. The arrays are views valid during the call.")
      .def(
          "use_exchange",
          [](S& self, nb::object exchange, nb::object owned_nodes, nb::object owned_cells) {
            self.state->use_exchange(nullptr);
            self.exchange.reset();
            if (exchange.is_none()) return;
            self.exchange = std::make_unique<PythonExchange<D>>(exchange, owned_nodes, owned_cells);
            const auto& g = self.state->grid();
            if (self.exchange->owned_nodes().size() != g.nnodes ||
                self.exchange->owned_cells().size() != g.ncells) {
              self.exchange.reset();
              throw std::invalid_argument("use_exchange: one owned flag per node and per cell");
            }
            self.state->use_exchange(self.exchange.get());
          },
          nb::arg("exchange").none(), nb::arg("owned_nodes").none() = nb::none(),
          nb::arg("owned_cells").none() = nb::none(),
          "Where the step meets the other ranks (src/core/exchange.hpp): an object with "
          "particles(), fill_nodes(*arrays), fill_cells(*arrays), own_unknowns(node_row), "
          "max(x), sum(n) and migrate(), and the nodes and cells this rank owns (bool "
          "arrays). None: one process alone.")
      .def(
          "advance",
          [](S& self, Array<double> x, Array<double> v, Array<double> mass, Array<double> volume,
             Array<double> pressure, const O& opt, index_t first, index_t nsteps, Report& report,
             const Affine& affine, const Affine& stress, const Affine& plastic_strain,
             const Affine& yielding) {
            auto P = particles<D>(x, v, mass, volume, pressure, affine, stress, plastic_strain,
                                  yielding);
            return run_chunk([&](const auto& between) {
              return self.state->advance(P, opt, first, nsteps, report, between);
            });
          },
          MPMFLOW_PARTICLE_ARGS, nb::arg("options"), nb::arg("first"), nb::arg("nsteps"),
          nb::arg("report"), MPMFLOW_AFFINE_ARG,
          "nsteps steps; returns the steps done (fewer: report.status says why).")
      .def(
          "advance_span",
          [](S& self, Array<double> x, Array<double> v, Array<double> mass, Array<double> volume,
             Array<double> pressure, const O& opt, double span, index_t max_steps, Report& report,
             const Affine& affine, const Affine& stress, const Affine& plastic_strain,
             const Affine& yielding) {
            auto P = particles<D>(x, v, mass, volume, pressure, affine, stress, plastic_strain,
                                  yielding);
            return run_chunk([&](const auto& between) {
              return self.state->advance_span(P, opt, span, max_steps, report, between);
            });
          },
          MPMFLOW_PARTICLE_ARGS, nb::arg("options"), nb::arg("span"), nb::arg("max_steps"),
          nb::arg("report"), MPMFLOW_AFFINE_ARG,
          "Adaptive steps over the span (s); returns the time covered.")
      .def_prop_rw(
          "since_volume", [](S& self) { return self.state->since_volume(); },
          [](S& self, double t) { self.state->set_since_volume(t); })
      .def(
          "set_bodies",
          [](S& self, nb::list bodies, nb::object fixed_no_slip, index_t nsub) {
            auto& keep = self.keep;
            std::vector<Body<D>> list;
            for (nb::handle item : bodies) {
              nb::dict d = nb::cast<nb::dict>(item);
              Body<D> b;
              b.phi = table<double, 1>(d["phi"], "body phi", keep);
              const auto counts = nb::cast<std::vector<index_t>>(d["counts"]);
              const auto origin = nb::cast<std::vector<double>>(d["origin"]);
              const auto lo = nb::cast<std::vector<double>>(d["lo"]);
              const auto hi = nb::cast<std::vector<double>>(d["hi"]);
              const auto axis = nb::cast<std::vector<double>>(d["axis"]);
              if (counts.size() != D || origin.size() != D || lo.size() != D || hi.size() != D ||
                  axis.size() != 3)
                throw std::invalid_argument(
                    "set_bodies: counts, origin, lo, hi need D entries, axis 3");
              index_t total = 1;
              for (int k = 0; k < D; ++k) {
                b.counts[k] = counts[k];
                b.origin[k] = origin[k];
                b.lo[k] = lo[k];
                b.hi[k] = hi[k];
                total *= counts[k];
              }
              for (int k = 0; k < 3; ++k) b.axis[k] = axis[k];
              if (b.phi.size() != total)
                throw std::invalid_argument("set_bodies: phi needs prod(counts) values");
              b.spacing = nb::cast<double>(d["spacing"]);
              b.free = d.contains("free") && nb::cast<bool>(d["free"]);
              if (b.free) {  // moved by the flow: its mass, inertia, held dofs and state
                b.mass = nb::cast<double>(d["mass"]);
                const auto inertia = nb::cast<std::vector<std::vector<double>>>(d["inertia"]);
                const auto locked = nb::cast<std::vector<bool>>(d["locked"]);
                const auto c = nb::cast<std::vector<double>>(d["centre_now"]);
                const auto v = nb::cast<std::vector<double>>(d["velocity_now"]);
                const auto w = nb::cast<std::vector<double>>(d["omega_now"]);
                const auto q = nb::cast<std::vector<double>>(d["quat"]);
                if (inertia.size() != 3 || locked.size() != 6 || c.size() != D || v.size() != D ||
                    w.size() != 3 || q.size() != 4 || !(b.mass > 0.0))
                  throw std::invalid_argument(
                      "set_bodies: a free body needs mass > 0, a 3 x 3 inertia, 6 locked "
                      "flags, D centre and velocity entries, 3 angular velocity entries and "
                      "a quaternion");
                for (int i = 0; i < 3; ++i) {
                  if (inertia[i].size() != 3)
                    throw std::invalid_argument("set_bodies: inertia must be 3 x 3");
                  for (int j = 0; j < 3; ++j) b.inertia[i][j] = inertia[i][j];
                  b.omega_now[i] = w[i];
                }
                for (int k = 0; k < 6; ++k) b.locked[k] = locked[k];
                for (int k = 0; k < D; ++k) {
                  b.centre_now[k] = c[k];
                  b.velocity_now[k] = v[k];
                }
                for (int k = 0; k < 4; ++k) b.quat[k] = q[k];
                if (d.contains("friction")) {
                  b.friction = nb::cast<double>(d["friction"]);
                  if (!(b.friction >= 0.0))
                    throw std::invalid_argument("set_bodies: friction must be >= 0");
                }
                if (d.contains("offset")) {
                  const auto o = nb::cast<std::vector<double>>(d["offset"]);
                  if (o.size() != D)
                    throw std::invalid_argument("set_bodies: offset needs D entries");
                  for (int k = 0; k < D; ++k) b.offset[k] = o[k];
                }
                if (d.contains("surface")) {
                  b.surface = table<double, 2>(d["surface"], "body surface", keep);
                  if (b.surface.size() > 0 && b.surface.extent(1) != D)
                    throw std::invalid_argument("set_bodies: surface points need D coordinates");
                }
              }
              b.time = table<double, 1>(d["time"], "body time", keep);
              b.centre = table<double, 2>(d["centre"], "body centre", keep);
              b.velocity = table<double, 2>(d["velocity"], "body velocity", keep);
              b.angle = table<double, 1>(d["angle"], "body angle", keep);
              b.rate = table<double, 1>(d["rate"], "body rate", keep);
              const index_t n = b.time.size();
              if ((n < 1 && !b.free) || b.centre.extent(0) != n || b.centre.extent(1) != D ||
                  b.velocity.extent(0) != n || b.velocity.extent(1) != D || b.angle.size() != n ||
                  b.rate.size() != n)
                throw std::invalid_argument(
                    "set_bodies: a path needs n times, n x D centres and velocities, n angles "
                    "and rates");
              for (index_t j = 1; j < n; ++j)
                if (!(b.time(j) > b.time(j - 1)))
                  throw std::invalid_argument("set_bodies: a path's times must increase");
              b.no_slip = nb::cast<bool>(d["no_slip"]);
              list.push_back(b);
            }
            const auto flags = table<bool, 1>(fixed_no_slip, "fixed_no_slip", keep);
            if (flags.size() > 0 && flags.size() != self.state->grid().nnodes)
              throw std::invalid_argument("set_bodies: fixed_no_slip needs one flag per node");
            self.state->set_bodies(std::move(list), flags, nsub);
          },
          nb::arg("bodies"), nb::arg("fixed_no_slip"), nb::arg("nsub"),
          "Obstacles moving along prescribed paths (src/core/bodies.hpp): each a dict of its "
          "body-frame distance lattice (phi, flat, axis 0 fastest; counts, origin, spacing), "
          "its shape's body-frame bounds (lo, hi), rotation axis (3 entries), path (time, "
          "centre, velocity, angle, rate) and no_slip flag. Places them at the state's time.")
      .def_prop_rw(
          "time", [](S& self) { return self.state->time(); },
          [](S& self, double t) { self.state->set_time(t); },
          "The flow time (s); setting it places the moving bodies.")
      .def_prop_rw(
          "body_state", &state_view<D, &State<D>::body_state>,
          [](S& self, Array<double> rows) {
            auto in = view<double, 2>(rows, "body_state");
            if (in.extent(0) != self.state->body_count() || in.extent(1) != 13)
              throw std::invalid_argument("body_state: one row of 13 values per body");
            self.state->set_body_state(in);
          },
          "Each body's pivot (3, m), velocity (3, m/s), angular velocity (3, rad/s) and "
          "orientation quaternion (4) at the state's time (a view, filled when read; 2D: z "
          "entries 0, rotation about z). Setting it puts the free bodies back (a checkpoint).")
      .def_prop_ro("body_force", &state_view<D, &State<D>::body_force>,
                   "The material's force on each body in the last step (bodies x D; N, 2D N/m): "
                   "a fluid's pressure, a solid's reactions at the nodes the body holds.")
      .def_prop_ro("body_torque", &state_view<D, &State<D>::body_torque>,
                   "The material's torque on each body about its frame's origin in the last "
                   "step (bodies x 3; N m, 2D N m/m).")
      .def(
          "set_inlet_pool",
          [](S& self, index_t first, index_t end) {
            if (first < 0 || end < first)
              throw std::invalid_argument("set_inlet_pool: need 0 <= first <= end");
            self.state->set_inlet_pool(first, end);
          },
          nb::arg("first"), nb::arg("end"),
          "The dormant particles [first, end) the inlets may emit in the next chunk (the "
          "particle arrays given to it must hold them).")
      .def_prop_ro(
          "inlet_next", [](S& self) { return self.state->inlet_next(); },
          "The first particle of the pool not emitted yet.")
      .def_prop_ro("inlet_travel", &state_view<D, &State<D>::inlet_travel>,
                   "Where each inlet row's next particle is (m: its centre lies travel - spacing "
                   "inside the side), a view (writable: a checkpoint restores it).")
      .def(
          "predict",
          [](S& self, Array<double> x, Array<double> v, Array<double> mass, Array<double> volume,
             Array<double> pressure, const O& opt, bool correct, const Affine& affine,
             const Affine& stress, const Affine& plastic_strain, const Affine& yielding) {
            auto P = particles<D>(x, v, mass, volume, pressure, affine, stress, plastic_strain,
                                  yielding);
            return self.state->predict(P, opt, correct);
          },
          MPMFLOW_PARTICLE_ARGS, nb::arg("options"), nb::arg("correct"), MPMFLOW_AFFINE_ARG,
          "scatter, then classify; returns the pressure unknowns.")
      .def(
          "scatter",
          [](S& self, Array<double> x, Array<double> v, Array<double> mass, Array<double> volume,
             Array<double> pressure, const O& opt, bool correct, const Affine& affine,
             const Affine& stress, const Affine& plastic_strain, const Affine& yielding) {
            auto P = particles<D>(x, v, mass, volume, pressure, affine, stress, plastic_strain,
                                  yielding);
            self.state->scatter(P, opt, correct);
          },
          MPMFLOW_PARTICLE_ARGS, nb::arg("options"), nb::arg("correct"), MPMFLOW_AFFINE_ARG,
          "The particles to the grid: binning, node mass, volume, v_old, v* (and cell_vol when "
          "correct), v* into the obstacles, node_f.")
      .def(
          "classify",
          [](S& self, Array<double> x, Array<double> v, Array<double> mass, Array<double> volume,
             Array<double> pressure, const O& opt) {
            auto P = particles<D>(x, v, mass, volume, pressure);
            return self.state->classify(P, opt);
          },
          MPMFLOW_PARTICLE_ARGS, nb::arg("options"),
          "The enclosed cells, the cells' integrals and the unknowns, from scatter's arrays and "
          "the particles it binned; returns the pressure unknowns.")
      .def(
          "renumber", [](S& self) { return self.state->renumber(); },
          "Rows again from node_row (>= 0: an unknown, -1: not), in classify's order; returns "
          "the pressure unknowns.")
      .def(
          "pressure_solve",
          [](S& self, const O& opt, Report& report) {
            nb::gil_scoped_release release;
            return self.state->pressure_solve(opt, report);
          },
          nb::arg("options"), nb::arg("report"),
          "The pressure step after predict (assembly, solves, wall release, ghost values); "
          "returns a Status.")
      .def("warm_start", [](S& self) { self.state->warm_start(); })
      .def("pressure_matrix",
           [](S& self, const O& opt) { return self.state->pressure_matrix(opt); })
      .def_prop_ro("pockets", [](S& self) { return self.state->pockets(); })
      .def("pressure_rhs", [](S& self, const O& opt) { self.state->pressure_rhs(opt); })
      .def("extend_pressure", [](S& self, const O& opt) { self.state->extend_pressure(opt); })
      .def("viscous_predictor",
           [](S& self, const O& opt, Report& report) {
             return self.state->viscous_predictor(opt, report);
           })
      .def(
          "viscous_start",
          [](S& self, const O& opt, Report& report) { self.state->viscous_start(opt, report); },
          nb::arg("options"), nb::arg("report"),
          "The viscous predictor's start: the walls' contact, eta, viscous_base (v* corrected "
          "by the last pressure).")
      .def(
          "viscous_system", [](S& self, const O& opt) { return self.state->viscous_system(opt); },
          nb::arg("options"),
          "The viscous predictor's system from viscous_base, not solved: viscous_rows, "
          "viscous_off, viscous_cols, viscous_vals, viscous_rhs and viscous_x (the start). "
          "Returns the unknowns (0 without a viscous material).")
      .def(
          "viscous_apply",
          [](S& self, Array<const double> x) {
            self.state->viscous_apply(view<const double>(x, "x"));
          },
          nb::arg("x"),
          "x (one value per unknown of the last viscous_system, m/s) into v_star, the held "
          "nodes at their held values.")
      .def(
          "finish",
          [](S& self, Array<double> x, Array<double> v, Array<double> mass, Array<double> volume,
             Array<double> pressure, const O& opt, bool correct, Report& report,
             const Affine& affine, const Affine& stress, const Affine& plastic_strain,
             const Affine& yielding) {
            auto P = particles<D>(x, v, mass, volume, pressure, affine, stress, plastic_strain,
                                  yielding);
            return self.state->finish(P, opt, correct, report);
          },
          MPMFLOW_PARTICLE_ARGS, nb::arg("options"), nb::arg("correct"), nb::arg("report"),
          MPMFLOW_AFFINE_ARG, "correct, the volume correction (when correct), to_particles.")
      .def(
          "correct", [](S& self, const O& opt) { self.state->correct(opt); }, nb::arg("options"),
          "v_new: the corrected velocity with the walls' and obstacles' conditions.")
      .def(
          "volume_system", [](S& self, const O& opt) { return self.state->volume_system(opt); },
          nb::arg("options"),
          "The volume correction's cell-centred system from cell_vol (a scatter with correct) "
          "and the pressure step's wall contact: volume_rows, volume_cols, volume_vals, "
          "volume_rhs, volume_air, volume_anchored, cell_row; its sealed pockets made "
          "solvable when options.pockets and the system is anchored. Returns the rows.")
      .def(
          "volume_apply",
          [](S& self, const O& opt, Array<const double> q) {
            return self.state->volume_apply(opt, view<const double>(q, "q"));
          },
          nb::arg("options"), nb::arg("q"),
          "q (one value per row of the last volume_system) into volume_q and the faces' "
          "displacements to_particles(displaced=True) adds; zero faces, q ignored, when that "
          "system had no rows or was not anchored. Returns the faces clamped.")
      .def(
          "to_particles",
          [](S& self, Array<double> x, Array<double> v, Array<double> mass, Array<double> volume,
             Array<double> pressure, const O& opt, bool displaced, const Affine& affine,
             const Affine& stress, const Affine& plastic_strain, const Affine& yielding) {
            auto P = particles<D>(x, v, mass, volume, pressure, affine, stress, plastic_strain,
                                  yielding);
            return self.state->to_particles(P, opt, displaced);
          },
          MPMFLOW_PARTICLE_ARGS, nb::arg("options"), nb::arg("displaced"), MPMFLOW_AFFINE_ARG,
          "Grid to particles (with the volume correction's displacements when displaced), "
          "push-out, periodic wrap; the particles may be the first n of scatter's. Returns the "
          "particles put back inside.")
      .def_prop_ro("phase_seconds",
                   [](S& self) {
                     const auto& t = self.state->phase_seconds();
                     return std::vector<double>(t.begin(), t.end());
                   })
      .def(
          "set_plate",
          [](S& self, int axis, int side, double force) {
            self.state->set_plate(axis, side, force);
          },
          nb::arg("axis"), nb::arg("side"), nb::arg("force"),
          "A rigid frictionless impermeable plate on the walls of one side (side -1: lower, "
          "+1: upper), pressed on the material with a total force (N; 2D N/m; along the axis).")
      .def_prop_rw(
          "plate_velocity", [](S& self) { return self.state->plate_velocity(); },
          [](S& self, double v) { self.state->set_plate_velocity(v); },
          "The plate's velocity along its axis (m/s).")
      .def_prop_ro("p_node", &state_view<D, &State<D>::p_node>)
      .def_prop_ro("p_cell", &state_view<D, &State<D>::p_cell>)
      .def_prop_ro("v_new", &state_view<D, &State<D>::v_new>)
      .def_prop_ro("contact", &state_view<D, &State<D>::contact>)
      .def_prop_ro("eta", &state_view<D, &State<D>::eta>)
      .def_prop_ro("ocontact", &state_view<D, &State<D>::ocontact>)
      .def_prop_ro("volume_q", &state_view<D, &State<D>::volume_q>)
      .def_prop_ro("rows", &state_view<D, &State<D>::rows>)
      .def_prop_ro("node_mass", &state_view<D, &State<D>::node_mass>)
      .def_prop_ro("node_vol", &state_view<D, &State<D>::node_vol>)
      .def_prop_ro("v_old", &state_view<D, &State<D>::v_old>)
      .def_prop_ro("v_star", &state_view<D, &State<D>::v_star>)
      .def_prop_ro("node_f", &state_view<D, &State<D>::node_f>)
      .def_prop_ro("node_row", &state_view<D, &State<D>::node_row>)
      .def_prop_ro("theta", &state_view<D, &State<D>::theta>)
      .def_prop_ro("cell_vol", &state_view<D, &State<D>::cell_vol>)
      .def_prop_ro("anchored", &state_view<D, &State<D>::anchored>)
      .def_prop_ro("matrix_cols", &state_view<D, &State<D>::matrix_cols>)
      .def_prop_ro("matrix_vals", &state_view<D, &State<D>::matrix_vals>)
      .def_prop_ro("rhs", &state_view<D, &State<D>::rhs>)
      .def_prop_ro("x0", &state_view<D, &State<D>::x0>)
      .def_prop_ro("volume_rows", &state_view<D, &State<D>::volume_rows>)
      .def_prop_ro("volume_cols", &state_view<D, &State<D>::volume_cols>)
      .def_prop_ro("volume_vals", &state_view<D, &State<D>::volume_vals>)
      .def_prop_ro("volume_rhs", &state_view<D, &State<D>::volume_rhs>)
      .def_prop_ro("volume_air", &state_view<D, &State<D>::volume_air>)
      .def_prop_rw(
          "volume_anchored", [](S& self) { return self.state->volume_anchored(); },
          [](S& self, bool anchored) { self.state->set_volume_anchored(anchored); })
      .def_prop_ro("viscous_rows", &state_view<D, &State<D>::viscous_rows>)
      .def_prop_ro("viscous_off", &state_view<D, &State<D>::viscous_off>)
      .def_prop_ro("viscous_cols", &state_view<D, &State<D>::viscous_cols>)
      .def_prop_ro("viscous_vals", &state_view<D, &State<D>::viscous_vals>)
      .def_prop_ro("viscous_rhs", &state_view<D, &State<D>::viscous_rhs>)
      .def_prop_ro("viscous_base", &state_view<D, &State<D>::viscous_base>)
      .def_prop_ro("viscous_x", &state_view<D, &State<D>::viscous_x>)
      .def_prop_ro("cell_row", &state_view<D, &State<D>::cell_row>);
}

}  // namespace

void bind_step(nb::module_& m) {
  m.def("adaptive_dt", &adaptive_dt, nb::arg("vmax2"), nb::arg("courant"), nb::arg("h"),
        nb::arg("dt_max"), nb::arg("rest"),
        "The adaptive step's size (s), fitted to the rest of the span (step.hpp).");
  m.def("volume_due_fixed", &volume_due_fixed, nb::arg("number"), nb::arg("every"),
        "Fixed steps: the volume correction on step number (from 1) a multiple of every.");
  m.def(
      "volume_due_adaptive",
      [](double since, double dt, double rate, double interval) {
        const bool due = volume_due_adaptive(since, dt, rate, interval);
        return std::make_tuple(due, since);
      },
      nb::arg("since"), nb::arg("dt"), nb::arg("rate"), nb::arg("interval"),
      "Adaptive steps: (whether the volume correction is due, the flow time since it).");
  nb::class_<Report>(m, "Report")
      .def(nb::init<>())
      .def_rw("unknowns", &Report::unknowns)
      .def_rw("solves", &Report::solves)
      .def_rw("iterations", &Report::iterations)
      .def_rw("max_iterations", &Report::max_iterations)
      .def_rw("residual", &Report::residual)
      .def_rw("released", &Report::released)
      .def_rw("unsettled", &Report::unsettled)
      .def_rw("plastic_iterations", &Report::plastic_iterations)
      .def_rw("moved", &Report::moved)
      .def_rw("status", &Report::status)
      .def_rw("step", &Report::step)
      .def_rw("fail_iterations", &Report::fail_iterations)
      .def_rw("fail_residual", &Report::fail_residual)
      .def_rw("fail_node", &Report::fail_node)
      .def_rw("fail_size", &Report::fail_size)
      .def_rw("volume_iterations", &Report::volume_iterations)
      .def_rw("last_unknowns", &Report::last_unknowns)
      .def_rw("viscous_iterations", &Report::viscous_iterations)
      .def_rw("steps", &Report::steps)
      .def_rw("dt_min", &Report::dt_min)
      .def_rw("dt_max", &Report::dt_max)
      .def_rw("capped", &Report::capped)
      .def_rw("clamped", &Report::clamped)
      .def_rw("pockets", &Report::pockets);
  m.attr("OK") = static_cast<int>(OK);
  m.attr("SINGULAR") = static_cast<int>(SINGULAR);
  m.attr("PRESSURE_NOT_CONVERGED") = static_cast<int>(PRESSURE_NOT_CONVERGED);
  m.attr("VOLUME_NOT_CONVERGED") = static_cast<int>(VOLUME_NOT_CONVERGED);
  m.attr("VISCOUS_NOT_CONVERGED") = static_cast<int>(VISCOUS_NOT_CONVERGED);
  m.attr("INTERRUPTED") = static_cast<int>(INTERRUPTED);
  m.attr("PLASTIC_NOT_CONVERGED") = static_cast<int>(PLASTIC_NOT_CONVERGED);
  m.attr("GAUSS") = static_cast<int>(GAUSS);
  m.attr("DIVERGENCE") = static_cast<int>(DIVERGENCE);
  m.attr("CONSISTENT") = static_cast<int>(CONSISTENT);
  m.attr("PHASES") = std::vector<std::string>{"binning",
                                              "particle to grid",
                                              "free surface (node fractions, classify)",
                                              "cell integrals (quadrature)",
                                              "viscous predictor",
                                              "pressure (assembly, multigrid, PCG, walls)",
                                              "corrector and walls",
                                              "volume correction",
                                              "grid to particle"};
  bind_dim<2>(m);
  bind_dim<3>(m);
}

}  // namespace mpmflow::bind
