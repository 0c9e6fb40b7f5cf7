// One registration function per concept; module.cpp calls them all.
#pragma once

#include <nanobind/nanobind.h>

namespace mpmflow::bind {

namespace nb = nanobind;

void bind_binning(nb::module_& m);
void bind_quadrature(nb::module_& m);
void bind_free_surface(nb::module_& m);
void bind_ghost_pressure(nb::module_& m);
void bind_pressure_system(nb::module_& m);
void bind_walls(nb::module_& m);
void bind_multigrid(nb::module_& m);
void bind_step(nb::module_& m);
void bind_transfer(nb::module_& m);
void bind_corrector(nb::module_& m);
void bind_volume_correction(nb::module_& m);
void bind_cut_cells(nb::module_& m);
void bind_viscous(nb::module_& m);
void bind_solid(nb::module_& m);
void bind_explicit_scheme(nb::module_& m);
void bind_totals(nb::module_& m);
void bind_pockets(nb::module_& m);

}  // namespace mpmflow::bind
