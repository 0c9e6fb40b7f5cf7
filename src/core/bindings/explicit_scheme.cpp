#include "../explicit_scheme.hpp"

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_explicit_scheme(nb::module_& m) {
  m.def(
      "cell_state",
      [](Array<const double> x, Array<const double> mass, Array<const double> volume,
         double density, double bulk, double tension, double h, std::vector<index_t> cells,
         double full, double sparse, Array<double> cell_j, Array<double> cell_vol,
         Array<double> cell_v0, Array<double> cell_xi, Array<double> cell_p) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          cell_state<D>(make_grid<D>(h, cells), view<const double, 2>(x, "x"),
                        view<const double>(mass, "mass"), view<const double>(volume, "volume"),
                        density, bulk, tension, full, sparse, view<double>(cell_j, "cell_j"),
                        view<double>(cell_vol, "cell_vol"), view<double>(cell_v0, "cell_v0"),
                        view<double, 2>(cell_xi, "cell_xi"), view<double>(cell_p, "cell_p"));
        });
      },
      "Explicit scheme: volumetric strain and pressure once per cell (in place).");
  m.def(
      "particle_state",
      [](Array<const double> x, Array<const double> mass, Array<double> volume,
         Array<double> pressure, double density, double h, std::vector<index_t> cells,
         bool smoothing, Array<const double> cell_j, Array<const double> cell_vol,
         Array<const double> cell_p, Array<double> node_w, Array<double> node_p) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          particle_state<D>(make_grid<D>(h, cells), view<const double, 2>(x, "x"),
                            view<const double>(mass, "mass"), view<double>(volume, "volume"),
                            view<double>(pressure, "pressure"), density, smoothing,
                            view<const double>(cell_j, "cell_j"),
                            view<const double>(cell_vol, "cell_vol"),
                            view<const double>(cell_p, "cell_p"), view<double>(node_w, "node_w"),
                            view<double>(node_p, "node_p"));
        });
      },
      "Explicit scheme: each particle's volume and pressure from its cell's state.");
  m.def(
      "max_speed", [](Array<const double> v) { return max_speed(view<const double, 2>(v, "v")); },
      "The largest particle speed (m/s); NaN if any speed is NaN.");
  m.def(
      "explicit_steps",
      [](double span, index_t nsteps, double safety, Array<double> x, Array<double> v,
         Array<double> pressure, Array<const double> mass, Array<double> volume, double density,
         double bulk, Array<const double> gravity, double h, std::vector<index_t> cells,
         double flip_ms, Array<const bool> no_slip, bool smoothing, double full, double sparse,
         double mass_cut, double q_lin, double q_quad, double tension, double max_speed_,
         Array<const double> upper, double margin, Array<double> node_mass, Array<double> node_mom,
         Array<double> v_old, Array<double> v_new, Array<bool> contact, Array<double> cell_j,
         Array<double> cell_vol, Array<double> cell_v0, Array<double> cell_xi, Array<double> cell_p,
         Array<double> cell_q, Array<double> node_w, Array<double> node_p, Array<double> stats) {
        ExplicitStats st;
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          if (no_slip.ndim() != 1 || no_slip.shape(0) != 2 * D)
            throw std::invalid_argument(
                "explicit_steps: no_slip needs 2 D flags (x_min, x_max, ...)");
          st = explicit_steps<D>(
              make_grid<D>(h, cells), span, nsteps, safety, view<double, 2>(x, "x"),
              view<double, 2>(v, "v"), view<double>(pressure, "pressure"),
              view<const double>(mass, "mass"), view<double>(volume, "volume"), density, bulk,
              view<const double>(gravity, "gravity"), flip_ms, view<const bool>(no_slip, "no_slip"),
              smoothing, full, sparse, mass_cut, q_lin, q_quad, tension, max_speed_,
              view<const double>(upper, "upper"), margin, view<double>(node_mass, "node_mass"),
              view<double, 2>(node_mom, "node_mom"), view<double, 2>(v_old, "v_old"),
              view<double, 2>(v_new, "v_new"), view<bool, 2>(contact, "contact"),
              view<double>(cell_j, "cell_j"), view<double>(cell_vol, "cell_vol"),
              view<double>(cell_v0, "cell_v0"), view<double, 2>(cell_xi, "cell_xi"),
              view<double>(cell_p, "cell_p"), view<double>(cell_q, "cell_q"),
              view<double>(node_w, "node_w"), view<double>(node_p, "node_p"));
        });
        auto s = view<double>(stats, "stats");
        s(0) = static_cast<double>(st.steps);
        s(1) = st.time;
        s(2) = st.smallest;
        s(3) = static_cast<double>(st.moved);
        s(4) = st.stopped ? 1.0 : 0.0;
        s(5) = st.vmax;
      },
      "Explicit steps over span seconds (in place); stats: [steps, time advanced, smallest "
      "step, particles put back inside, 1 if stopped on max_speed, largest speed].");
}

}  // namespace mpmflow::bind
