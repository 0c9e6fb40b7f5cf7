// The exchange seam (issue 42; docs/design/mpi.md, section 2): the points where a step of
// a domain split over ranks meets the other ranks, called from inside the step's phases
// (step.cpp): the halo of particles, filling the nodes a rank holds without owning them,
// the owners' say on the pressure unknowns, reductions, and particle migration. The step's
// three systems (pressure, viscous, volume) are solved across ranks by the step's solvers
// (LinearSolver, ViscousSolver: step.hpp), which number their rows over the ranks.
//
// This class is one process alone: every call is the identity, and a State uses it unless
// given another. A rank's implementation (bindings/step.cpp, PythonExchange) calls
// mpmflow.parallel, whose exchanges use MPI.
#pragma once

#include "particles.hpp"
#include "view.hpp"

namespace mpmflow {

template <int D>
class Exchange {
 public:
  virtual ~Exchange() = default;
  // whether other ranks share the domain (false: every call below changes nothing)
  virtual bool shared() const { return false; }
  // A step's particles: alone, the run's own; on a rank, its own particles and after them
  // the halo (copies of its neighbours' particles in its ghost layer), in its local grid's
  // coordinates. The views stay valid until the next call or migrate().
  virtual Particles<D> particles(const Particles<D>& own) { return own; }
  // how many of a step's particles, the first ones, this rank moves (the others: the halo)
  virtual index_t owned(const Particles<D>& P) { return P.count(); }
  // The owners' values at the nodes (cells) a rank holds without owning them, for count
  // arrays of one row per node (cell) each, overwritten there. Collective.
  virtual void fill_nodes(const View<double, 2>* fields, int count) {}
  virtual void fill_cells(const View<double, 2>* fields, int count) {}
  // The owners' decision on which nodes are pressure unknowns (node_row >= 0) at the nodes
  // a rank holds without owning them; the caller numbers its rows again. Collective.
  virtual void own_unknowns(View<index_t> node_row) {}
  // reductions over the ranks (collective)
  virtual double max(double x) { return x; }
  virtual index_t sum(index_t x) { return x; }
  // each value summed over the ranks, in place (the bodies' forces and torques)
  virtual void sum_values(View<double> values) {}
  // The halo's stress (a solid's) made its owners' again after they updated it, before the
  // step reads the stress of every particle round a node (a solid's tools). Collective over
  // the neighbours.
  virtual void refresh_halo() {}
  // After a step: each of the rank's particles to the rank that owns its new cell.
  // Collective over the neighbours.
  virtual void migrate() {}
  // the nodes and cells a rank owns, one flag each (empty: every one); the step counts
  // what it reports (unknowns, wall releases, capped cells) on these only
  virtual View<const bool> owned_nodes() { return {}; }
  virtual View<const bool> owned_cells() { return {}; }
};

}  // namespace mpmflow
