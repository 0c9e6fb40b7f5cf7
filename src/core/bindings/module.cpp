// mpmflow._core: the compiled core. Python reaches it only through mpmflow.state.
#include <nanobind/nanobind.h>

#include "../parallel.hpp"
#include "modules.hpp"

namespace nb = nanobind;

NB_MODULE(_core, m) {
  // Objects still referenced when the interpreter exits (a Simulation kept by a test or a
  // user's session) are freed by the OS; nanobind's report of them at exit is noise.
  nb::set_leak_warnings(false);
  m.doc() = "mpmflow's compiled core (C++17, OpenMP): kernels of the projection scheme.";
  m.def("max_threads", &mpmflow::max_threads, "OpenMP threads a parallel loop uses.");
  m.def("set_threads", &mpmflow::set_threads, nb::arg("n"),
        "Set the OpenMP threads of the following parallel loops.");
  m.attr("CHUNKS") = mpmflow::CHUNKS;
#ifdef NDEBUG
  m.attr("DEBUG") = false;
#else
  m.attr("DEBUG") = true;
#endif
  mpmflow::bind::bind_binning(m);
  mpmflow::bind::bind_quadrature(m);
  mpmflow::bind::bind_free_surface(m);
  mpmflow::bind::bind_ghost_pressure(m);
  mpmflow::bind::bind_pressure_system(m);
  mpmflow::bind::bind_walls(m);
  mpmflow::bind::bind_multigrid(m);
  mpmflow::bind::bind_step(m);
  mpmflow::bind::bind_transfer(m);
  mpmflow::bind::bind_corrector(m);
  mpmflow::bind::bind_volume_correction(m);
  mpmflow::bind::bind_cut_cells(m);
  mpmflow::bind::bind_viscous(m);
  mpmflow::bind::bind_solid(m);
  mpmflow::bind::bind_explicit_scheme(m);
  mpmflow::bind::bind_totals(m);
  mpmflow::bind::bind_pockets(m);
}
