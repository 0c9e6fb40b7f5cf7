// One registration function per concept; module.cpp calls them all.
#pragma once

#include <nanobind/nanobind.h>

namespace mpmflow::bind {

namespace nb = nanobind;

void bind_binning(nb::module_& m);
void bind_explicit_scheme(nb::module_& m);

}  // namespace mpmflow::bind
