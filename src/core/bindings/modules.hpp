// One registration function per concept; module.cpp calls them all.
#pragma once

#include <nanobind/nanobind.h>

namespace mpmflow::bind {

namespace nb = nanobind;

void bind_binning(nb::module_& m);
void bind_viscous(nb::module_& m);
void bind_multigrid(nb::module_& m);

}  // namespace mpmflow::bind
