#include "../multigrid.hpp"

#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

namespace {

// A Multigrid<D> with the arrays of its finest level: the object views them without a
// copy, so it holds them until the next setup.
template <int D>
struct PyMultigrid {
  Multigrid<D> mg;
  Array<const index_t> cols, node;
  Array<const double> vals;
};

template <int D>
void bind_class(nb::module_& m, const char* name) {
  using P = PyMultigrid<D>;
  nb::class_<P>(m, name,
                "Multigrid-preconditioned CG on a structured grid: a hierarchy set up once "
                "for a matrix (ELL, 3^D slots) and reused by later setups.")
      .def(nb::init<>())
      .def(
          "setup",
          [](P& self, Array<const index_t> cols, Array<const double> vals,
             Array<const index_t> node, std::vector<index_t> dims, index_t coarsest) {
            if (dims.size() != static_cast<std::size_t>(D))
              throw std::invalid_argument("dims: one number of points per axis");
            std::array<index_t, D> d{};
            for (int k = 0; k < D; ++k) d[k] = dims[static_cast<std::size_t>(k)];
            auto c = view<const index_t, 2>(cols, "cols");
            auto v = view<const double, 2>(vals, "vals");
            auto nd = view<const index_t>(node, "node");
            self.mg.setup(c, v, nd, d, coarsest);
            self.cols = cols;  // held until the next setup
            self.vals = vals;
            self.node = node;
          },
          nb::arg("cols"), nb::arg("vals"), nb::arg("node"), nb::arg("dims"),
          nb::arg("coarsest") = COARSEST, "Build the levels (the arrays are held, not copied).")
      .def(
          "pcg",
          [](P& self, Array<const double> rhs, Array<double> x, double tol, index_t maxiter,
             int sweeps) {
            SolveResult s = self.mg.pcg(view<const double>(rhs, "rhs"), view<double>(x, "x"), tol,
                                        maxiter, sweeps);
            return std::make_pair(s.iterations, s.residual);
          },
          nb::arg("rhs"), nb::arg("x").noconvert(), nb::arg("tol"), nb::arg("maxiter"),
          nb::arg("sweeps"),
          "Preconditioned CG from x (updated in place): (iterations, true relative residual).")
      .def(
          "vcycle",
          [](P& self, Array<const double> b, Array<double> x, int sweeps) {
            self.mg.vcycle(view<const double>(b, "b"), view<double>(x, "x"), sweeps);
          },
          nb::arg("b"), nb::arg("x").noconvert(), nb::arg("sweeps"),
          "One V-cycle with zero initial guess: x = M^-1 b.")
      .def(
          "refresh", [](P& self) { self.mg.refresh(); },
          "The finest level's values changed in place (the held vals array): read them again.")
      .def("levels", [](const P& self) { return self.mg.levels(); })
      .def("rows", [](const P& self) { return self.mg.rows(); });
}

}  // namespace

void bind_multigrid(nb::module_& m) {
  m.attr("COARSEST") = COARSEST;
  m.attr("PARALLEL_ROWS") = PARALLEL_ROWS;
  bind_class<2>(m, "Multigrid2");
  bind_class<3>(m, "Multigrid3");
  m.def(
      "matvec",
      [](Array<const index_t> cols, Array<const double> vals, Array<const double> x,
         Array<double> y) {
        matvec(view<const index_t, 2>(cols, "cols"), view<const double, 2>(vals, "vals"),
               view<const double>(x, "x"), view<double>(y, "y"));
      },
      nb::arg("cols"), nb::arg("vals"), nb::arg("x"), nb::arg("y").noconvert(), "y = A x.");
  m.def(
      "residual",
      [](Array<const index_t> cols, Array<const double> vals, Array<const double> x,
         Array<const double> b, Array<double> out) {
        residual(view<const index_t, 2>(cols, "cols"), view<const double, 2>(vals, "vals"),
                 view<const double>(x, "x"), view<const double>(b, "b"), view<double>(out, "out"));
      },
      nb::arg("cols"), nb::arg("vals"), nb::arg("x"), nb::arg("b"), nb::arg("out").noconvert(),
      "out = b - A x.");
  m.def(
      "dot",
      [](Array<const double> a, Array<const double> b) {
        return dot(view<const double>(a, "a"), view<const double>(b, "b"));
      },
      "a . b, chunked (CHUNKS) when long: the same bits on any thread count.");
  m.def(
      "worst_row",
      [](Array<const index_t> cols, Array<const double> vals, Array<const double> x,
         Array<const double> b, Array<double> r) {
        return worst_row(view<const index_t, 2>(cols, "cols"), view<const double, 2>(vals, "vals"),
                         view<const double>(x, "x"), view<const double>(b, "b"),
                         view<double>(r, "r"));
      },
      nb::arg("cols"), nb::arg("vals"), nb::arg("x"), nb::arg("b"), nb::arg("r").noconvert(),
      "The row of the largest |b - A x| (NaN counts as largest); r: scratch.");
}

}  // namespace mpmflow::bind
