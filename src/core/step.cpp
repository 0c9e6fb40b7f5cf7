#include "step.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "binning.hpp"
#include "cell_pressure.hpp"
#include "complementarity.hpp"
#include "corrector.hpp"
#include "cut_cells.hpp"
#include "dense.hpp"
#include "free_surface.hpp"
#include "ghost_pressure.hpp"
#include "parallel.hpp"
#include "periodic.hpp"
#include "plasticity.hpp"
#include "pockets.hpp"
#include "pressure_system.hpp"
#include "quadrature.hpp"
#include "rheology.hpp"
#include "solid.hpp"
#include "transfer.hpp"
#include "viscous.hpp"
#include "volume_correction.hpp"
#include "walls.hpp"

namespace mpmflow {

namespace {

// Adds the seconds from its construction to the next lap (or its end) to a phase's total.
class PhaseClock {
 public:
  explicit PhaseClock(std::array<double, NPHASES>& totals) : totals_(totals), t_(now()) {}
  void lap(int phase) {
    const double t = now();
    totals_[phase] += t - t_;
    t_ = t;
  }

 private:
  static double now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }
  std::array<double, NPHASES>& totals_;
  double t_;
};
}  // namespace

template <int D>
State<D>::State(const Grid<D>& grid, double cell_volume, const std::array<double, D>& lower,
                const std::array<double, D>& upper, double margin, const GridTables<D>& tables,
                bool volume_correction, bool viscous)
    : grid_(grid),
      cell_volume_(cell_volume),
      lower_(lower),
      upper_(upper),
      margin_(margin),
      T_(tables),
      volume_on_(volume_correction),
      viscous_on_(viscous),
      obstacles_(tables.phi.size() > 0) {
  ob_.phi = T_.phi;
  ob_.open = T_.open;
  ob_.static_slot = T_.static_slot;
  ob_.K = T_.K_static;
  ob_.C = T_.C_static;
  ob_.V = T_.V_static;
  ob_.F = T_.F_static;
  ob_.Wf = T_.Wf_static;
  ob_.onode = T_.onode;
  ob_.onormal = T_.onormal;
  ob_.ono_slip = T_.ono_slip;
  const index_t nn = grid_.nnodes, nc = grid_.ncells;
  travel_.assign(static_cast<std::size_t>(T_.inlets.rows()), 0.0);
  start_.reserve(nc + 1);
  theta_.reserve(nc);
  node_mass_.reserve(nn);
  node_mom_.reserve(nn * D);
  node_vol_.reserve(nn);
  v_old_.reserve(nn * D);
  v_star_.reserve(nn * D);
  v_c_.reserve(nn * D);
  v_new_.reserve(nn * D);
  node_f_.reserve(nn);
  dep_t_.reserve(nn);
  enclosed_.reserve(nc);
  slot_.reserve(nc);
  surface_slot_.reserve(nc);
  node_row_.reserve(nn);
  node_row_.view(nn);
  for (index_t i = 0; i < nn; ++i) node_row_.view(nn)(i) = -1;
  rows_.reserve(nn);
  contact_.reserve(nn * D);
  ocontact_.reserve(nn);
  anchored_.reserve(nn);
  p_node_.reserve(nn);
  for (index_t i = 0; i < nn; ++i) p_node_.view(nn)(i) = 0.0;
  p_cell_.reserve(nc);  // zeros (calloc)
  for (index_t i = 0; i < nn * D; ++i) v_new_.view(nn * D)(i) = 0.0;
  for (index_t i = 0; i < nn; ++i) ocontact_.view(nn)(i) = false;
  partial_.reserve(nc);
  listed_.reserve(nc);
  if (volume_on_) {
    cell_vol_.reserve(nc);
    density_.reserve(nc);
    cell_row_.reserve(nc);
    vol_cols_.reserve(nc * NS);
    vol_vals_.reserve(nc * NS);
    vol_rhs_.reserve(nc);
    vol_rows_.reserve(nc);
    vol_air_.reserve(nc);
    for (index_t c = 0; c < nc; ++c) cell_row_.view(nc)(c) = -1;
    q_.reserve(nc);
    qx_.reserve(nc);
    for (index_t c = 0; c < nc; ++c) q_.view(nc)(c) = 0.0;
    for (int k = 0; k < D; ++k) {
      index_t n = 1;
      for (int j = 0; j < D; ++j) n *= grid_.cells[j] + (j == k ? 1 : 0);
      faces_[k].reserve(n);
      for (index_t i = 0; i < n; ++i) faces_[k].view(n)(i) = 0.0;
    }
  }
  if (viscous_on_) {
    eta_.reserve(nc);
    eta_weight_.reserve(nc);
    vu_.reserve(nn * D);
    v_rate_.reserve(nn * D);
    vrow_.reserve(nn * D);
    voff_.reserve(D + 1);
  }
}

template <int D>
void State<D>::set_bodies(std::vector<Body<D>> bodies, View<const bool> fixed_no_slip,
                          index_t nsub) {
  ObstacleTables<D> fixed = ob_;
  fixed.velocity = View<const double, 2>();
  bodies_.setup(grid_, fixed, fixed_no_slip, std::move(bodies), nsub);
  {  // a rank's grid: its first node in the domain's, which ends where the grid's upper does
    std::array<index_t, D> origin{}, cells{};
    for (int k = 0; k < D; ++k) {
      origin[k] = static_cast<index_t>(std::llround(-lower_[k] * grid_.inv_h));
      cells[k] = static_cast<index_t>(std::llround(upper_[k] * grid_.inv_h)) + origin[k];
    }
    bodies_.set_domain(origin, cells);
  }
  body_force_.sized(bodies_.count() * D);
  body_torque_.sized(bodies_.count() * 3);
  for (index_t i = 0; i < bodies_.count() * D; ++i) body_force_.view(bodies_.count() * D)(i) = 0.0;
  for (index_t i = 0; i < bodies_.count() * 3; ++i) body_torque_.view(bodies_.count() * 3)(i) = 0.0;
  obstacles_ = true;
  set_time(time_);
}

template <int D>
void State<D>::set_time(double t) {
  time_ = t;
  if (!bodies_.present()) return;
  bodies_.place(t);
  bodies_.hold(t);
  ob_ = bodies_.tables();
  auto ocontact = ocontact_.view(grid_.nnodes);
  for (index_t i = 0; i < grid_.nnodes; ++i) ocontact(i) = false;
}

template <int D>
void State<D>::bin_particles(const Particles<D>& P) {
  const index_t n = P.count();
  const index_t nc = grid_.ncells;
  auto cell = cell_.sized(n);
  auto order = order_.sized(n);
  auto start = start_.view(nc + 1);
  auto theta = theta_.view(nc);
  cell_index<D>(grid_, P.x, cell);
  sort_with_fraction(cell, nc, P.volume, cell_volume_, ob_.open, start, order, theta);
  if (obstacles_) sliver_fractions<D>(grid_, ob_.open, theta, bodies_.present());
  binned_ = n;
}

template <int D>
void State<D>::cell_integrals(const Particles<D>& P, const Options<D>& O) {
  // which cells take part in the pressure system and their element integrals (slot 0: the
  // Gauss tensors, 1 to nstatic - 1: the cut cells, then the cells' own particle tensors)
  const index_t nc = grid_.ncells;
  auto theta = theta_.view(nc);
  auto enclosed = enclosed_.view(nc);
  auto slot = slot_.view(nc);
  auto stat = ob_.static_slot;
  const index_t ns = ob_.K.extent(0);
  const bool particles = O.partial_particles || O.cell_pressure;
  index_t npartial = 0, nsurface = 0;
  for (index_t c = 0; c < nc; ++c) {
    const bool counted = theta(c) >= O.sparse;
    slot(c) = (counted || enclosed(c)) && stat(c) >= 0 ? stat(c) : -1;
    if (counted && theta(c) < O.full && stat(c) >= 0) {
      if (particles)
        npartial += 1;
      else if (!enclosed(c))
        nsurface += 1;
    }
  }
  const index_t nk = npartial + ns;
  auto K = K_.template sized<3>({nk, NC, NC});
  auto C = C_.template sized<4>({nk, NC, NC, D});
  auto V = V_.template sized<2>({nk, NC});
  std::copy(ob_.K.data(), ob_.K.data() + ob_.K.size(), K.data());
  std::copy(ob_.C.data(), ob_.C.data() + ob_.C.size(), C.data());
  std::copy(ob_.V.data(), ob_.V.data() + ob_.V.size(), V.data());
  auto start = start_.view(nc + 1);
  auto order = order_.view(P.count());
  if (npartial) {
    auto partial = partial_.view(npartial);
    index_t m = 0;
    for (index_t c = 0; c < nc; ++c) {
      if (theta(c) >= O.sparse && theta(c) < O.full && stat(c) >= 0) {
        slot(c) = ns + m;
        partial(m) = c;
        m += 1;
      }
    }
    particle_cell_tensors<D>(grid_, P.x, P.volume, order, start, partial,
                             View<double, 3>(K.data() + ns * NC * NC, {npartial, NC, NC}),
                             View<double, 4>(C.data() + ns * NC * NC * D, {npartial, NC, NC, D}),
                             View<double, 2>(V.data() + ns * NC, {npartial, NC}));
  }
  I_.slot = slot;
  I_.K = K;
  if (O.surface == GAUSS || particles) {
    I_.rhs_slot = I_.cor_slot = slot;
    I_.rhs_C = I_.cor_C = C;
    I_.rhs_V = I_.cor_V = V;
    return;
  }
  auto surface_slot = surface_slot_.view(nc);
  auto listed = listed_.view(nsurface);
  index_t m = 0;
  for (index_t c = 0; c < nc; ++c) {
    surface_slot(c) = slot(c);
    if (theta(c) >= O.sparse && theta(c) < O.full && !enclosed(c) && stat(c) >= 0) {
      surface_slot(c) = ns + m;
      listed(m) = c;
      m += 1;
    }
  }
  const index_t nsk = nsurface + ns;
  auto Cs = Cs_.template sized<4>({nsk, NC, NC, D});
  auto Vs = Vs_.template sized<2>({nsk, NC});
  auto Vcells = Vcells_.template sized<2>({nsk, NC});
  std::copy(ob_.C.data(), ob_.C.data() + ob_.C.size(), Cs.data());
  std::copy(ob_.V.data(), ob_.V.data() + ob_.V.size(), Vs.data());
  std::copy(ob_.V.data(), ob_.V.data() + ob_.V.size(), Vcells.data());
  for (index_t s = ns; s < nsk; ++s)
    for (int a = 0; a < NC; ++a) Vcells(s, a) = ob_.V(0, a);
  if (nsurface) {
    particle_cell_tensors<D>(grid_, P.x, P.volume, order, start, listed,
                             View<double, 3>(nullptr, {0, NC, NC}),
                             View<double, 4>(Cs.data() + ns * NC * NC * D, {nsurface, NC, NC, D}),
                             View<double, 2>(Vs.data() + ns * NC, {nsurface, NC}));
  }
  I_.rhs_slot = surface_slot;
  I_.rhs_C = Cs;
  I_.rhs_V = Vcells;
  if (O.surface == CONSISTENT) {
    I_.cor_slot = surface_slot;
    I_.cor_C = Cs;
    I_.cor_V = Vs;
  } else {
    I_.cor_slot = slot;
    I_.cor_C = C;
    I_.cor_V = V;
  }
}

template <int D>
void State<D>::classify_nodes(const Options<D>& O) {
  const index_t nn = grid_.nnodes;
  auto node_row = node_row_.view(nn);
  nrows_ = mpmflow::classify_nodes<D>(grid_, I_.slot, ob_.static_slot, node_f_.view(nn), O.subcell,
                                      node_row, O.cell_pressure);
  shallow_ = false;  // until shallow_nodes takes them out
  fill_rows();
  if (O.cell_pressure) {  // a solid's pressure per cell: its rows and their gradients
    const index_t nc = grid_.ncells;
    npc_ = number_cells(I_.cor_slot, pc_row_.sized(nc), pc_rows_.sized(nc));
    cell_gradients<D>(grid_, I_.cor_slot, I_.cor_C, pc_rows_.view(npc_),
                      pc_G_.template sized<3>({npc_, NC, D}));
    node_volumes<D>(grid_, I_.cor_slot, node_mass_.view(nn), O.rho, pc_vol_.sized(nn));
  }
}

template <int D>
void State<D>::fill_rows() {
  const index_t nn = grid_.nnodes;
  auto node_row = node_row_.view(nn);
  auto rows = rows_.view(nrows_);
  // downwards, so that a row an image shares with its master (periodic axes) ends on the
  // master, the lower index
  for (index_t i = nn - 1; i >= 0; --i) {
    const index_t r = node_row(i);
    if (r >= 0) rows(r) = i;
  }
}

template <int D>
index_t State<D>::renumber() {
  nrows_ = renumber_nodes<D>(grid_, node_row_.view(grid_.nnodes));
  fill_rows();
  return nrows_;
}

template <int D>
bool State<D>::shallow_nodes(const Options<D>& O) {
  // unknowns too near the surface for a bounded extrapolation become interpolated nodes,
  // decided by each node's owner from the owners' unknowns
  const index_t nn = grid_.nnodes;
  shallow_ = O.subcell && O.shallow > 0.0 && O.dt < O.shallow_max_dt && !O.cell_pressure;
  if (!shallow_) return false;
  auto node_row = node_row_.view(nn);
  auto dep = dep_t_.view(nn);
  demote_shallow<D>(grid_, I_.slot, I_.K, node_row, node_f_.view(nn), O.shallow, dep);
  if (exchange_->shared()) {
    const View<double, 2> fields[] = {dep_t_.template view<2>({nn, 1})};
    exchange_->fill_nodes(fields, 1);
  }
  bool any = false;
  for (index_t i = 0; i < nn; ++i)
    if (dep(i) >= 0.0) {
      node_row(i) = -1;
      any = true;
    }
  return any;
}

template <int D>
index_t State<D>::predict(const Particles<D>& P, const Options<D>& O, bool correct) {
  scatter(P, O, correct);
  const bool shared = exchange_->shared();
  const index_t nn = grid_.nnodes, nc = grid_.ncells;
  if (shared) {  // the owners' values at the nodes (and cells) round a rank's box
    const View<double, 2> nodes[] = {
        node_mass_.template view<2>({nn, 1}), node_vol_.template view<2>({nn, 1}),
        v_old_.template view<2>({nn, D}), v_star_.template view<2>({nn, D}),
        node_f_.template view<2>({nn, 1})};
    exchange_->fill_nodes(nodes, 5);
    // the cells' particle volume reaches past a cell: the owners' sums
    if (correct) {
      const View<double, 2> cells[] = {cell_vol_.template view<2>({nc, 1})};
      exchange_->fill_cells(cells, 1);
    }
  }
  classify(P, O);
  if (shared) {  // the owners decide which nodes round the box are unknowns, then shallow
    exchange_->own_unknowns(node_row_.view(nn));
    shallow_nodes(O);
    renumber();
  }
  return nrows_;
}

namespace {
// the rows whose place (node or cell: rows(r)) a part owns (owned empty: every row)
index_t owned_places(View<const bool> owned, View<const index_t> rows) {
  if (owned.size() == 0) return rows.size();
  index_t n = 0;
  for (index_t r = 0; r < rows.size(); ++r) n += owned(rows(r)) ? 1 : 0;
  return n;
}
}  // namespace

template <int D>
index_t State<D>::owned_rows() {
  return owned_places(exchange_->owned_nodes(), rows_.view(nrows_));
}

template <int D>
index_t State<D>::owned_cell_rows() {
  return owned_places(exchange_->owned_cells(), pc_rows_.view(npc_));
}

template <int D>
template <class Release>
index_t State<D>::releases(Release&& release) {
  if (!exchange_->shared()) return release();
  const index_t before = owned_contacts();
  release();
  return exchange_->sum(before - owned_contacts());
}

template <int D>
index_t State<D>::owned_contacts() {
  const auto owned = exchange_->owned_nodes();
  const index_t nn = grid_.nnodes;
  auto contact = contact_.template view<2>({nn, D});
  auto ocontact = ocontact_.view(nn);
  index_t n = 0;
  for (index_t i = 0; i < nn; ++i) {
    if (owned.size() > 0 && !owned(i)) continue;
    for (int k = 0; k < D; ++k) n += contact(i, k) ? 1 : 0;
    n += ocontact(i) ? 1 : 0;
  }
  return n;
}

template <int D>
void State<D>::scatter(const Particles<D>& P, const Options<D>& O, bool correct) {
  const index_t nn = grid_.nnodes, nc = grid_.ncells;
  PhaseClock clock(phase_seconds_);
  bin_particles(P);
  clock.lap(PHASE_BINNING);
  auto v_old = v_old_.template view<2>({nn, D});
  auto v_star = v_star_.template view<2>({nn, D});
  particles_to_grid<D>(grid_, P.x, P.v, P.mass, P.volume, order_.view(P.count()),
                       start_.view(nc + 1), View<const double>(O.gravity.data(), {D}), O.dt,
                       node_mass_.view(nn), node_mom_.template view<2>({nn, D}), node_vol_.view(nn),
                       v_old, v_star, correct ? cell_vol_.view(nc) : View<double>(), P.affine);
  solid_scattered_ = P.stress.size() > 0 && is_solid(O.model);
  if (solid_scattered_) {  // a solid: its cells' yielded share, its old stress's force
    cell_mean<D>(grid_, P.mass, P.yielding, order_.view(P.count()), start_.view(nc + 1),
                 cell_yield_.sized(nc));
    if (O.model == POROELASTIC)  // a saturated soil's cells: their share of free water
      water_share<D>(grid_, P.mass, P.volume, O.model_params[3], order_.view(P.count()),
                     start_.view(nc + 1), cell_water_.sized(nc));
    internal_forces<D>(grid_, P.x, P.volume, P.stress, order_.view(P.count()), start_.view(nc + 1),
                       node_mass_.view(nn), O.dt, force_.template sized<2>({nn, D}), v_star);
  }
  if (T_.load.size() > 0) {  // the surface loads (boundaries/loads.py)
    auto mass = node_mass_.view(nn);
    parallel_for(nn, [&](index_t i) {
      if (mass(i) > 0.0)
        for (int k = 0; k < D; ++k) v_star(i, k) += O.dt * T_.load(i, k) / mass(i);
    });
  }
  if (obstacles_) extend_velocity<D>(grid_, ob_.onode, node_mass_.view(nn), v_old, v_star);
  clock.lap(PHASE_P2G);
  // with moving obstacles, a node beside one whose cells all hold material is inside it
  nodal_fraction<D>(grid_, theta_.view(nc), ob_.open, node_f_.view(nn), bodies_.present(),
                    O.sparse);
  clock.lap(PHASE_FREE_SURFACE);
}

template <int D>
index_t State<D>::classify(const Particles<D>& P, const Options<D>& O) {
  if (P.count() != binned_)
    throw std::invalid_argument("State::classify: the particles the last scatter binned, " +
                                std::to_string(binned_) + ", and " + std::to_string(P.count()) +
                                " given");
  const index_t nn = grid_.nnodes, nc = grid_.ncells;
  PhaseClock clock(phase_seconds_);
  auto enclosed = enclosed_.view(nc);
  if (O.subcell) {
    enclosed_cells<D>(grid_, node_f_.view(nn), enclosed);
  } else {
    for (index_t c = 0; c < nc; ++c) enclosed(c) = false;
  }
  clock.lap(PHASE_FREE_SURFACE);
  cell_integrals(P, O);
  clock.lap(PHASE_INTEGRALS);
  classify_nodes(O);
  // on ranks after the owners' unknowns (predict)
  if (!exchange_->shared() && shallow_nodes(O)) renumber();
  clock.lap(PHASE_FREE_SURFACE);
  return nrows_;
}

template <int D>
void State<D>::warm_start() {
  const index_t nn = grid_.nnodes;
  auto x = x_.sized(nrows_);
  auto rows = rows_.view(nrows_);
  auto p = p_node_.view(nn);
  for (index_t r = 0; r < nrows_; ++r) x(r) = p(rows(r));
  for (index_t i = 0; i < nn; ++i) p(i) = 0.0;
}

template <int D>
bool State<D>::pressure_matrix(const Options<D>& O) {
  const index_t nn = grid_.nnodes;
  npockets_ = 0;
  auto v_star = v_star_.template view<2>({nn, D});
  auto node_row = node_row_.view(nn);
  start_contact(T_.wall_node, T_.wall_axis, T_.wall_sign, v_star, node_row,
                contact_.template view<2>({nn, D}), T_.wall_bonded);
  start_obstacles(ob_.onode, ob_.onormal, v_star, node_row, ocontact_.view(nn), ob_.velocity);
  const index_t n = nrows_;
  auto cols = cols_.template sized<2>({n, NS});
  auto vals = vals_.template sized<2>({n, NS});
  auto anchored = anchored_.sized(n);
  rhs_.reserve(n);  // the right-hand side and the solver's scratch, grown here, not in a solve
  scratch_.reserve(n);
  if (n == 0) return false;
  assemble_matrix<D>(grid_, I_.slot, I_.K, node_row, node_f_.view(nn), O.subcell, O.theta_min, cols,
                     vals, anchored, shallow(nn));
  for (index_t r = 0; r < n; ++r)
    if (anchored(r)) {
      if (O.pockets) anchor_pockets(O);
      return true;
    }
  return false;
}

template <int D>
void State<D>::anchor_pockets(const Options<D>& O) {
  // water sealed off from the free surface (src/core/pockets.hpp): its pressure is fixed up to
  // a constant only, set by p = 0 at its highest node (against gravity), so that it presses
  // on its walls (p >= 0 under gravity) and the contact conditions hold it
  const index_t n = nrows_;
  auto rows = rows_.view(n);
  auto anchored = anchored_.view(n);
  npockets_ = find_pockets(
      cols_.template view<2>({n, NS}), vals_.template view<2>({n, NS}),
      [&](index_t r) { return anchored(r); },
      [&](index_t r) {
        index_t ix[D];
        grid_.node_coords(rows(r), ix);
        double z = 0.0;
        for (int k = 0; k < D; ++k) z -= O.gravity[k] * static_cast<double>(ix[k]);
        return z;
      },
      component_.sized(n), pocket_order_.sized(n), pockets_.sized(n));
  pocket_mean_.reserve(2 * npockets_);
}

template <int D>
void State<D>::pressure_rhs(const Options<D>& O) {
  const index_t nn = grid_.nnodes;
  auto v_c = v_star_.template view<2>({nn, D});
  auto contact = contact_.template view<2>({nn, D});
  auto ocontact = ocontact_.view(nn);
  if (!O.wall_flux) {  // the paper: the divergence of the wall-constrained v*
    v_c = v_c_.template view<2>({nn, D});
    std::copy(v_star_.view(nn * D).data(), v_star_.view(nn * D).data() + nn * D, v_c.data());
    apply_walls(T_.wall_node, T_.wall_axis, T_.wall_sign, T_.wall_no_slip, v_c, contact,
                T_.wall_velocity);
    apply_obstacles(ob_.onode, ob_.onormal, ob_.ono_slip, v_c, ocontact, View<const double>(),
                    ob_.velocity);
  }
  assemble_rhs<D>(grid_, I_.rhs_slot, I_.rhs_C, I_.rhs_V, node_vol_.view(nn), rows_.view(nrows_),
                  v_c, contact, O.wall_flux, O.expansion / O.dt, O.rho / O.dt, ob_.static_slot,
                  ob_.F, ob_.Wf, ocontact, T_.wall_velocity, rhs_.view(nrows_), ob_.velocity);
  if (npockets_ > 0) {
    auto mean = pocket_mean_.view(2 * npockets_);
    apply_pockets(component_.view(nrows_), pockets_.view(npockets_), mean.head(npockets_),
                  View<double>(mean.data() + npockets_, {npockets_}), rhs_.view(nrows_));
  }
}

template <int D>
void State<D>::extend_pressure(const Options<D>& O) {
  const index_t nn = grid_.nnodes;
  if (!O.subcell) return;
  if (shallow_) {
    shallow_values<D>(grid_, I_.slot, I_.K, node_row_.view(nn), shallow(nn), p_node_.view(nn));
    if (exchange_->shared()) {  // the owners' at the halo: its ghosts extrapolate from them
      const View<double, 2> p[] = {p_node_.template view<2>({nn, 1})};
      exchange_->fill_nodes(p, 1);
    }
  }
  ghost_values<D>(grid_, I_.slot, I_.K, node_row_.view(nn), node_f_.view(nn), O.theta_min,
                  p_node_.view(nn), shallow(nn));
}

template <int D>
template <class Solve>
bool State<D>::couple_bodies(const Options<D>& O, Solve& solve) {
  // The free bodies' velocities q are unknowns of the pressure step with it: the right-hand
  // side just solved (p0 = A^-1 r) took them at q*, and q = q* + dt M^-1 K p, so that
  //   (A + rho J M^-1 K) p = r,
  // J, K the coupling of bodies.hpp. The update is of rank nq (the free degrees of freedom):
  // by the Woodbury identity p = p0 - Y S^-1 K p0 with Y = A^-1 J (nq more solves of the
  // same matrix) and S = M / rho + K Y (nq x nq).
  const index_t n = nrows_, nq = bodies_.free_dofs(), nn = grid_.nnodes;
  auto J = body_J_.template sized<2>({nq, n});
  auto K = body_K_.template sized<2>({nq, n});
  auto Y = body_Y_.template sized<2>({nq, n});
  auto S = body_S_.template sized<2>({nq, nq});
  auto z = body_z_.sized(nq);
  bodies_.coupling(I_.slot, node_row_.view(nn), ocontact_.view(nn), J, K);
  auto zero = zero_.view(n);  // the contact's rows held at p = 0: no coupling there
  for (index_t d = 0; d < nq; ++d)
    for (index_t r = 0; r < n; ++r)
      if (zero(r)) J(d, r) = K(d, r) = 0.0;
  for (index_t d = 0; d < nq; ++d) {
    View<double> y(&Y(d, 0), {n});
    for (index_t r = 0; r < n; ++r) y(r) = 0.0;
    if (!solve(View<const double>(&J(d, 0), {n}), y)) return false;
  }
  auto x = x_.view(n);
  // K's products over the rows: on several ranks each rank's owned rows, then summed over
  // the ranks (the solves gave Y and x at every row a rank holds), so that every rank
  // moves the bodies alike
  const bool shared = exchange_->shared();
  const auto owned = exchange_->owned_nodes();
  auto rows = rows_.view(n);
  const auto mine = [&](index_t r) { return owned.size() == 0 || owned(rows(r)); };
  auto KY = body_KY_.sized(nq * nq + nq);  // K Y (nq x nq), then K p0 (nq)
  for (index_t i = 0; i < nq; ++i) {
    for (index_t j = 0; j < nq; ++j) {
      double v = 0.0;
      for (index_t r = 0; r < n; ++r)
        if (mine(r)) v += K(i, r) * Y(j, r);
      KY(i * nq + j) = v;
    }
    double kp = 0.0;
    for (index_t r = 0; r < n; ++r)
      if (mine(r)) kp += K(i, r) * x(r);
    KY(nq * nq + i) = kp;
  }
  if (shared) exchange_->sum_values(KY);
  bodies_.mass_matrix(S);
  for (index_t i = 0; i < nq; ++i) {
    for (index_t j = 0; j < nq; ++j) S(i, j) = S(i, j) / O.rho + KY(i * nq + j);
    z(i) = KY(nq * nq + i);
  }
  // z = S^-1 K p0 (S = M / rho + K Y is positive definite: a zero pivot is not a coupling)
  if (!solve_dense(nq, S.data(), z.data()))
    throw std::logic_error("State: the free bodies' coupling matrix is singular");
  for (index_t d = 0; d < nq; ++d)
    for (index_t r = 0; r < n; ++r) x(r) -= Y(d, r) * z(d);
  // the pressure's impulse on the bodies, dt K p, and their velocities after it
  for (index_t d = 0; d < nq; ++d) {
    double kp = 0.0;
    for (index_t r = 0; r < n; ++r)
      if (mine(r)) kp += K(d, r) * x(r);
    z(d) = kp;
  }
  if (shared) exchange_->sum_values(z);
  for (index_t d = 0; d < nq; ++d) z(d) *= O.dt;
  bodies_.apply_impulse(z);
  bodies_.hold(time_ + 0.5 * O.dt);
  return true;
}

template <int D>
bool State<D>::counted_solve(const Options<D>& O, Report& report, View<const index_t, 2> cols,
                             View<const double, 2> vals, View<const index_t> rows,
                             View<const double> b, View<double> y, View<double> scratch,
                             index_t& iterations, bool cells, double tol) {
  if (solver_ || !(tol > 0.0)) tol = O.tol;  // (a caller's solver takes its own)
  const SolveResult res =
      solver_ ? solver_->solve(b, y) : pressure_mg_.pcg(b, y, tol, O.max_iterations, O.sweeps);
  report.solves += 1;
  report.iterations += res.iterations;
  iterations += res.iterations;
  // (a looser solve, a preconditioner's, is not the system's residual)
  report.residual =
      std::max(report.residual, tol > O.tol ? std::min(res.residual, O.tol) : res.residual);
  if (res.residual <= tol) return true;
  report.fail_iterations = res.iterations;
  report.fail_residual = res.residual;
  const index_t worst = rows(worst_row(cols, vals, y, b, scratch));
  // a cell's row: its first node, for the message's place
  report.fail_node = cells ? grid_.cell_first_node(worst) : worst;
  report.fail_size = rows.size();
  return false;
}

template <int D>
void State<D>::cell_hold() {
  const index_t nn = grid_.nnodes;
  hold_projector(T_.wall_node, T_.wall_axis, T_.wall_no_slip, contact_.template view<2>({nn, D}),
                 ob_.onode, ob_.onormal, ob_.ono_slip, ocontact_.view(nn),
                 pc_P_.template sized<3>({nn, D, D}));
}

template <int D>
typename State<D>::MgShape State<D>::mg_shape(bool nodes) const {
  MgShape shape;
  for (int k = 0; k < D; ++k) {
    shape.dims[k] = grid_.cells[k] + (nodes ? 1 : 0);
    if (grid_.periodic[k]) shape.period[k] = grid_.cells[k];
  }
  return shape;
}

template <int D>
View<const double> State<D>::water_cells(const Options<D>& O) {
  if (O.model != POROELASTIC || !solid_scattered_) return {};
  return cell_water_.view(grid_.ncells);
}

template <int D>
int State<D>::cell_pressure_solve(const Options<D>& O, Report& report) {
  // on a rank: its local cells' rows (its own and the ghost layer's, whose particles the halo
  // brings), solved over the ranks by its solver, which numbers the rows each rank owns and
  // gives the ghost layer's rows their owners' values; every rank takes part in each solve
  const bool shared = exchange_->shared();
  if (shared && !solver_)
    throw std::logic_error("State: a rank's cell pressure needs a solver over the ranks");
  if (bodies_.free_dofs() > 0)
    throw std::logic_error("State: a solid's cell pressure does not take free bodies");
  const index_t nn = grid_.nnodes, nc = grid_.ncells, n = npc_;
  auto v_star = v_star_.template view<2>({nn, D});
  auto node_row = node_row_.view(nn);
  auto contact = contact_.template view<2>({nn, D});
  auto ocontact = ocontact_.view(nn);
  start_contact(T_.wall_node, T_.wall_axis, T_.wall_sign, v_star, node_row, contact,
                T_.wall_bonded);
  start_obstacles(ob_.onode, ob_.onormal, v_star, node_row, ocontact, ob_.velocity);
  auto p_cell = p_cell_.view(nc);
  if (shared ? exchange_->sum(owned_cell_rows()) == 0 : n == 0) {
    for (index_t c = 0; c < nc; ++c) p_cell(c) = 0.0;
    cell_to_nodes<D>(grid_, I_.cor_slot, I_.cor_V, pc_row_.view(nc), pc_rows_.view(0), p_cell,
                     View<double, 2>(), View<double, 2>(), p_node_.view(nn));
    return OK;
  }
  auto rows = pc_rows_.view(n);
  auto cell_row = pc_row_.view(nc);
  auto G = pc_G_.template view<3>({n, NC, D});
  auto vol = pc_vol_.view(nn);
  auto cols = cols_.template sized<2>({n, NS});
  auto vals = vals_.template sized<2>({n, NS});
  auto rhs = rhs_.sized(n);
  auto x = x_.sized(n);
  auto scratch = scratch_.sized(n);
  for (index_t r = 0; r < n; ++r) x(r) = p_cell(rows(r));  // the last step's, to start from
  const auto [dims, period] = mg_shape(false);
  auto v = v_c_.template view<2>({nn, D});
  // a saturated soil: its pore water's flow between the cells joins each cell's constraint
  const double darcy = O.rho / O.dt * pore_mobility(O.model, O.model_params.data());
  if (shared && darcy > 0.0)  // (mpmflow.parallel.support refuses it by name)
    throw std::logic_error("State: a saturated soil's pore flow runs in one process");
  index_t step_iterations = 0;
  while (true) {
    cell_hold();
    assemble_cells<D>(grid_, cell_row, rows, G, pc_P_.template view<3>({nn, D, D}), vol, cols,
                      vals);
    darcy_matrix<D>(grid_, cell_row, rows, ob_.open, water_cells(O), darcy, cols, vals);
    std::copy(v_star.data(), v_star.data() + nn * D, v.data());
    apply_walls(T_.wall_node, T_.wall_axis, T_.wall_sign, T_.wall_no_slip, v, contact,
                T_.wall_velocity);
    apply_obstacles(ob_.onode, ob_.onormal, ob_.ono_slip, v, ocontact, View<const double>(),
                    ob_.velocity);
    cell_rhs<D>(grid_, rows, G, v, O.rho / O.dt, rhs);
    darcy_gravity<D>(grid_, cell_row, rows, ob_.open, water_cells(O), darcy, O.model_params[3],
                     O.gravity, rhs);
    if (solver_)
      solver_->setup(cols, vals, rows);
    else
      pressure_mg_.setup(cols, vals, rows, dims, COARSEST, period);
    if (!counted_solve(O, report, cols, vals, rows, rhs, x, scratch, step_iterations, true))
      return PRESSURE_NOT_CONVERGED;
    for (index_t c = 0; c < nc; ++c) p_cell(c) = 0.0;
    for (index_t r = 0; r < n; ++r) p_cell(rows(r)) = x(r);
    // the walls let go where the cells round a node pull (their plain mean is negative)
    auto mean = pc_mean_.sized(nn);
    cell_to_nodes<D>(grid_, I_.cor_slot, I_.cor_V, cell_row, rows, p_cell, View<double, 2>(),
                     View<double, 2>(), mean);
    // (a node round a rank's box sees every cell about it but at the ghost layer's outer
    // face, where only the ghost cells' rows, not a rank's own, read it)
    const index_t released = releases([&] {
      return release_contact(T_.wall_node, T_.wall_axis, T_.wall_sign, v_star, node_row, mean,
                             contact, T_.wall_bonded) +
             release_obstacles(ob_.onode, ob_.onormal, v_star, node_row, mean, ocontact,
                               ob_.velocity);
    });
    if (released == 0) break;
    report.released += released;
  }
  auto X = pc_X_.template sized<2>({n, D});
  auto grad = pc_grad_.template sized<2>({n, D});
  cell_slopes<D>(grid_, I_.cor_slot, I_.cor_V, cell_row, rows, p_cell, X, grad);
  if (shared) {  // the ghost layer's gradients: their owners' (their neighbours lie past it)
    auto cg = pc_cell_grad_.template sized<2>({nc, D});
    for (index_t c = 0; c < nc * D; ++c) cg.data()[c] = 0.0;
    for (index_t r = 0; r < n; ++r)
      for (int k = 0; k < D; ++k) cg(rows(r), k) = grad(r, k);
    const View<double, 2> fields[] = {cg};
    exchange_->fill_cells(fields, 1);
    for (index_t r = 0; r < n; ++r)
      for (int k = 0; k < D; ++k) grad(r, k) = cg(rows(r), k);
  }
  slopes_to_nodes<D>(grid_, I_.cor_slot, I_.cor_V, cell_row, p_cell, X, grad, p_node_.view(nn));
  if (shared) {  // the ghost layer's outer nodes: their owners' mean of every cell round them
    const View<double, 2> p[] = {p_node_.template view<2>({nn, 1})};
    exchange_->fill_nodes(p, 1);
  }
  report.max_iterations = std::max(report.max_iterations, step_iterations);
  return OK;
}

template <int D>
bool State<D>::elastic_velocity(const Options<D>& O, Report& report, View<double, 2> out) {
  const index_t nn = grid_.nnodes;
  const index_t n = viscous_system(O);
  auto vu = vu_.template view<2>({nn, D});
  auto vrow = vrow_.template view<2>({nn, D});
  if (n > 0 && !viscous_solve(O, report, n)) return false;
  auto x = vx_.view(n);
  for (index_t i = 0; i < nn; ++i)
    for (int k = 0; k < D; ++k) out(i, k) = vrow(i, k) >= 0 ? x(vrow(i, k)) : vu(i, k);
  return true;
}

template <int D>
int State<D>::coupled_solve(const Options<D>& O, Report& report, double loosen) {
  if (exchange_->shared())  // (mpmflow.parallel.support refuses it by name)
    throw std::logic_error("State: a solid's coupled step runs in one process");
  struct Still {  // the linear part's holds last only while the solve runs
    bool& on;
    ~Still() { on = false; }
  } still{held_still_};
  const index_t nn = grid_.nnodes, nc = grid_.ncells, n = npc_;
  if (n == 0) return OK;
  auto rows = pc_rows_.view(n);
  auto cell_row = pc_row_.view(nc);
  auto G = pc_G_.template view<3>({n, NC, D});
  auto P = pc_P_.template view<3>({nn, D, D});
  auto vol = pc_vol_.view(nn);
  auto v0 = cp_v0_.template view<2>({nn, D});
  auto base = v_c_.template view<2>({nn, D});
  auto x = cp_x_.template sized<2>({nn, D});
  auto dx = cp_dx_.template sized<2>({nn, D});
  auto cells = cp_cells_.template sized<2>({6, n});
  auto pr = cells.row(0), r = cells.row(1), z = cells.row(2), zold = cells.row(3), d = cells.row(4),
       q = cells.row(5);
  auto cols = cols_.template view<2>({n, NS});
  auto vals = vals_.template view<2>({n, NS});
  auto scratch = scratch_.sized(n);
  auto p_cell = p_cell_.view(nc);    // the split step's pressure: the first guess
  auto field = cp_field_.sized(nc);  // a cell-indexed vector for correct_cells
  const double dt_rho = O.dt / O.rho, rho_dt = O.rho / O.dt;
  const double cell_volume = std::pow(grid_.h, D);
  // the base velocity of pressure y (cells' values by row): v0 - dt / rho V^-1 P G^T y with
  // the walls and tools holding their components at their velocities; linear (the search
  // direction's part): from v0 = 0, the held components at 0 (P holds them: the contacts
  // the split step settled, fixed through the solve), the elastic solve's held values too
  auto set_base = [&](View<const double> y, bool affine) {
    for (index_t c = 0; c < nc; ++c) field(c) = 0.0;
    for (index_t k = 0; k < n; ++k) field(rows(k)) = y(k);
    held_still_ = !affine;
    if (affine) {
      correct_cells<D>(grid_, cell_row, G, P, vol, field, v0, dt_rho, base);
      apply_walls(T_.wall_node, T_.wall_axis, T_.wall_sign, T_.wall_no_slip, base,
                  contact_.template view<2>({nn, D}), T_.wall_velocity);
      apply_obstacles(ob_.onode, ob_.onormal, ob_.ono_slip, base, ocontact_.view(nn),
                      View<const double>(), ob_.velocity);
    } else {
      for (index_t i = 0; i < nn * D; ++i) dx.data()[i] = 0.0;
      correct_cells<D>(grid_, cell_row, G, P, vol, field, dx, dt_rho, base);
    }
  };
  // the preconditioner: the Poisson operator's inverse (its multigrid, set up by the split
  // step) plus eta_c dt / (rho V_c), the Schur complement's inverse where the elastic
  // stiffness dominates (eta_c = G dt, less a yielded cell's share, times a partial cell's
  // fraction: the elastic solve's own weight)
  index_t step_iterations = 0;
  auto weight = eta_weight_.view(nc);
  // (a saturated soil's skeleton resists a change of volume with 2 G + lambda where an
  // incompressible solid's shear has 2 G: the weight grows by 1 + lambda / (2 G))
  const double bulk = 0.5 * grad_div_ratio(O.model, O.model_params.data());
  const double per_volume = O.dt / (O.rho * cell_volume) * (1.0 + bulk);
  // a saturated soil's pore flow (cell_pressure.hpp: darcy_*)
  const double darcy = rho_dt * pore_mobility(O.model, O.model_params.data());
  // A saturated soil: at the steps of its consolidation the Schur complement is the
  // skeleton's stiffness term D (the inverse of the weight above) plus the pore flow's
  // matrix T, (rho / dt)(D + T), whose inverse is not the sum of the two parts' inverses:
  // off by up to 2 + r + 1 / r, r = T / D (about 2 c_v dt / h^2). Where the flow weighs
  // more than the stiffness, r >= PORE_RATIO, the preconditioner is one V-cycle of the
  // Poisson operator and one of D + T, assembled on the cells of soil (free water's rows:
  // none, as the weight gives none; both approximate: the solve is flexible). Measured:
  // Mandel's problem (r = 8) 2.6 times faster, 40 coupled iterations a step down to 12;
  // Terzaghi's column at r = 1.6, 1.5 times slower that way (its Poisson solve to the
  // tolerance and D's inverse end most steps within 2 iterations), so below the ratio the
  // preconditioner is the solids'.
  constexpr double PORE_RATIO = 4.0;
  bool pore = false;
  auto pc = pore_cols_.template sized<2>({darcy > 0.0 ? n : 0, NS});
  auto pv = pore_vals_.template sized<2>({darcy > 0.0 ? n : 0, NS});
  if (darcy > 0.0) {
    for (index_t k = 0; k < n * NS; ++k) {
      pc.data()[k] = -1;
      pv.data()[k] = 0.0;
    }
    darcy_matrix<D>(grid_, cell_row, rows, ob_.open, water_cells(O), darcy, pc, pv);
    double flow = 0.0, stiff = 0.0;
    for (index_t k = 0; k < n; ++k) {
      const double w = weight(rows(k)) * per_volume;
      if (w > 0.0) {
        flow += pv(k, NS / 2);
        stiff += 1.0 / w;
      }
    }
    pore = stiff > 0.0 && flow >= PORE_RATIO * stiff;
  }
  auto pz = pore_z_.sized(pore ? n : 0);
  if (pore) {
    for (index_t k = 0; k < n; ++k) {
      const double w = weight(rows(k)) * per_volume;
      if (w > 0.0) {
        pc(k, NS / 2) = k;
        pv(k, NS / 2) += 1.0 / w;
        for (int t = 0; t < NS; ++t)  // a neighbour of free water: held at 0 here
          if (pc(k, t) >= 0 && !(weight(rows(pc(k, t))) > 0.0)) {
            pc(k, t) = -1;
            pv(k, t) = 0.0;
          }
      } else {  // free water: a row of its own, whose part is 0
        for (int t = 0; t < NS; ++t) {
          pc(k, t) = -1;
          pv(k, t) = 0.0;
        }
        pc(k, NS / 2) = k;
        pv(k, NS / 2) = 1.0;
      }
    }
    const auto [dims, period] = mg_shape(false);
    pore_mg_.setup(pc, pv, rows, dims, COARSEST, period);
  }
  auto precondition = [&](View<const double> res, View<double> out) {
    for (index_t k = 0; k < n; ++k) out(k) = 0.0;
    if (pore) {
      pressure_mg_.vcycle(res, out, O.sweeps);
      pore_mg_.vcycle(res, pz, O.sweeps);
      for (index_t k = 0; k < n; ++k) out(k) += weight(rows(k)) > 0.0 ? pz(k) : 0.0;
      report.solves += 1;
      step_iterations += 1;
      return true;
    }
    // (the Poisson solve to PRECONDITIONER_TOL: the CG is flexible, and a solve to the
    // solver's tolerance cost the footing of examples/footing.toml at 2.5 times the shear
    // wave's step 3.6 times the multigrid's iterations for the same load to 1e-5)
    if (!counted_solve(O, report, cols, vals, rows, res, out, scratch, step_iterations, true,
                       std::max(O.tol, PRECONDITIONER_TOL)))
      return false;
    for (index_t k = 0; k < n; ++k) out(k) += weight(rows(k)) * per_volume * res(k);
    return true;
  };
  auto dot = [&](View<const double> a, View<const double> b) {
    double sum = 0.0;
    for (index_t k = 0; k < n; ++k) sum += a(k) * b(k);
    return sum;
  };
  // the scale: the size of the divergence's terms in v (a sum of magnitudes, which does
  // not vanish where v is divergence-free already, as in simple shear), v* for a solid; for
  // a saturated soil, those of the elastic velocity at the first pressure with the size of
  // its pore flows: as it consolidates at steps long for its inertia, v* is the load's
  // acceleration over the step, orders of magnitude above the velocity the pressure leaves
  auto terms = [&](View<const double, 2> v, View<const double> y, bool flows) {
    auto t = q;  // (q: free until the iterations)
    for (index_t k = 0; k < n; ++k) {
      const index_t first = grid_.cell_first_node(rows(k));
      double sum = 0.0;
      for (int a = 0; a < NC; ++a)
        for (int m = 0; m < D; ++m) sum += std::abs(G(k, a, m) * v(first + grid_.corner[a], m));
      t(k) = sum;
    }
    if (flows)
      darcy_magnitude<D>(grid_, cell_row, rows, ob_.open, water_cells(O), darcy / rho_dt,
                         O.model_params[3], O.gravity, y, t);
    double scale2 = 0.0;
    for (index_t k = 0; k < n; ++k) scale2 += rho_dt * rho_dt * t(k) * t(k);
    return scale2 > 0.0 ? std::sqrt(scale2) : 1.0;
  };
  for (index_t k = 0; k < n; ++k) pr(k) = p_cell(rows(k));
  double scale = darcy > 0.0 ? 0.0 : terms(v0, pr, false);
  // (a saturated soil: the residual cannot fall below the rounding of the elastic velocity
  // of v* without pressure, which free water at rest at a long step leaves at eps g dt)
  double floor = 0.0;
  if (darcy > 0.0) {
    for (index_t k = 0; k < n; ++k) z(k) = 0.0;
    set_base(z, true);
    if (!elastic_velocity(O, report, x)) return VISCOUS_NOT_CONVERGED;
    floor = 1e2 * std::numeric_limits<double>::epsilon() * terms(x, z, false);
  }
  set_base(pr, true);
  if (!elastic_velocity(O, report, x)) return VISCOUS_NOT_CONVERGED;
  cell_rhs<D>(grid_, rows, G, x, rho_dt, r);  // the residual: x's divergence
  darcy_gravity<D>(grid_, cell_row, rows, ob_.open, water_cells(O), darcy, O.model_params[3],
                   O.gravity, r);
  darcy_apply<D>(grid_, cell_row, rows, ob_.open, water_cells(O), -darcy, pr,
                 r);  // and the pores' outflow
  if (darcy > 0.0) scale = terms(x, pr, true);
  const double tol = std::max(1e2 * O.tol * scale * loosen, floor);
  index_t it = 0;
  double rz = 0.0;
  // not converged: the report names the cell of the largest divergence left
  auto not_converged = [&]() {
    index_t worst = 0;
    for (index_t k = 1; k < n; ++k)
      if (std::abs(r(k)) > std::abs(r(worst))) worst = k;
    report.fail_iterations = it;
    report.fail_residual = std::sqrt(dot(r, r)) / scale;
    report.fail_node = grid_.cell_first_node(rows(worst));
    report.fail_size = n;
    return PRESSURE_NOT_CONVERGED;
  };
  while (std::sqrt(dot(r, r)) > tol) {
    if (it == O.max_iterations) return not_converged();
    if (!precondition(r, z)) return PRESSURE_NOT_CONVERGED;
    if (it == 0) {
      for (index_t k = 0; k < n; ++k) d(k) = z(k);
    } else {  // flexible (Polak-Ribiere): the preconditioner is itself an iterative solve
      const double beta = (rz != 0.0) ? (dot(r, z) - dot(r, zold)) / rz : 0.0;
      for (index_t k = 0; k < n; ++k) d(k) = z(k) + beta * d(k);
    }
    rz = dot(r, z);
    for (index_t k = 0; k < n; ++k) zold(k) = z(k);
    // q = S d = -(rho / dt) C x_lin(d) + (rho / dt) T d, x_lin the elastic velocity of the
    // base -dt/rho V^-1 P G^T d, T the pores' flow (a saturated soil; else 0)
    set_base(d, false);
    if (!elastic_velocity(O, report, dx)) return VISCOUS_NOT_CONVERGED;
    cell_rhs<D>(grid_, rows, G, dx, rho_dt, q);
    for (index_t k = 0; k < n; ++k) q(k) = -q(k);
    darcy_apply<D>(grid_, cell_row, rows, ob_.open, water_cells(O), darcy, d, q);
    const double dq = dot(d, q);
    // S is positive definite: only rounding (or a fault) gets here
    if (!(dq > 0.0)) return not_converged();
    const double alpha = rz / dq;
    for (index_t k = 0; k < n; ++k) {
      pr(k) += alpha * d(k);
      r(k) -= alpha * q(k);
    }
    for (index_t i = 0; i < nn * D; ++i) x.data()[i] += alpha * dx.data()[i];
    it += 1;
  }
  report.max_iterations = std::max(report.max_iterations, step_iterations);
  // the pressure, and v_star such that the corrector gives x: v_star = x + dt/rho V^-1 P G^T p
  for (index_t c = 0; c < nc; ++c) p_cell(c) = 0.0;
  for (index_t k = 0; k < n; ++k) p_cell(rows(k)) = pr(k);
  for (index_t i = 0; i < nn * D; ++i) dx.data()[i] = 0.0;
  auto v_star = v_star_.template view<2>({nn, D});
  correct_cells<D>(grid_, cell_row, G, P, vol, p_cell, dx, dt_rho, v_star);  // -dt/rho V^-1 P G^T p
  for (index_t i = 0; i < nn * D; ++i) v_star.data()[i] = x.data()[i] - v_star.data()[i];
  cell_to_nodes<D>(grid_, I_.cor_slot, I_.cor_V, cell_row, rows, p_cell,
                   pc_X_.template sized<2>({n, D}), pc_grad_.template sized<2>({n, D}),
                   p_node_.view(nn));
  return OK;
}

template <int D>
int State<D>::plastic_solve(const Particles<D>& P, const Options<D>& O, Report& report) {
  // Fixed-point iterations on the particles' return factors a_p (solid.hpp, return_factors):
  // the coupled solve with each particle's stress after the step taken as a_p (s_p + 2 G dt
  // dev D), its old stress's force scaled by a_p and each cell's elastic weight G dt by its
  // particles' mean a_p, until the factors the solve's velocity gives are those it took:
  // the backward-Euler step of the radial return (the first solve is the yielded share's).
  // Plain iterations, a <- g(a): Anderson's mixing of the last 2-4 iterates took a footing
  // from 6-7 iterations a step to 5-6 at 2.5 times the shear wave's step, but did not
  // converge in 50 on the first steps of a suddenly loaded clay layer at 14 times, which
  // the plain iterations settle in 18 (docs/method.md, "Solids").
  const index_t nn = grid_.nnodes, nc = grid_.ncells, np = P.count();
  auto factor = ps_factor_.sized(np);
  for (index_t p = 0; p < np; ++p) factor(p) = 1.0;
  auto x = cp_x_.template view<2>({nn, D});
  auto v0 = cp_v0_.template view<2>({nn, D});
  // v* before the elastic increment with the whole old stress's force (the coupled solve
  // reads cp_v0_ and leaves it; the iterations below rewrite it)
  auto keep = ps_v0_.template sized<2>({nn, D});
  std::copy(v0.data(), v0.data() + nn * D, keep.data());
  auto force = force_.template view<2>({nn, D});
  auto scaled = ps_f_.template sized<2>({nn, D});
  auto mass = node_mass_.view(nn);
  auto mean = ps_mean_.sized(nc);
  auto whole = ps_weight_.view(nc);
  auto weight = eta_weight_.view(nc);
  const View<const double> par(O.model_params.data(), {8});
  auto share = cell_yield_.view(nc);
  bool yielded = false;
  for (index_t c = 0; c < nc && !yielded; ++c) yielded = share(c) > 0.0;
  for (index_t it = 0;; ++it) {
    // g(a) into factor (a: the last solve's)
    const double change =
        return_factors<D>(grid_, P.x, P.mass, View<const double, 2>(x.data(), {nn, D}),
                          p_node_.view(nn), O.dt, O.model, par, P.stress, factor);
    // (the first solve took the factors 1 where no particle had yielded in the last step)
    if ((it > 0 || !yielded) && change <= PLASTIC_TOL) return OK;
    if (it == PLASTIC_ITERATIONS) {
      report.fail_iterations = it;
      report.fail_residual = change;
      report.fail_size = np;
      return PLASTIC_NOT_CONVERGED;
    }
    report.plastic_iterations += 1;
    stress_forces<D>(grid_, P.x, P.volume, P.stress, order_.view(np), start_.view(nc + 1), scaled,
                     factor);
    parallel_for(nn, [&](index_t i) {
      for (int k = 0; k < D; ++k)
        v0(i, k) =
            mass(i) > 0.0 ? keep(i, k) + O.dt * (scaled(i, k) - force(i, k)) / mass(i) : keep(i, k);
    });
    cell_mean<D>(grid_, P.mass, factor, order_.view(np), start_.view(nc + 1), mean);
    for (index_t c = 0; c < nc; ++c) weight(c) = whole(c) * mean(c);
    // (the solve to PLASTIC_LOOSEN of the last change, where that is above its tolerance:
    // an iterate far from the fixed point needs no more; the footing at 2.5 times the shear
    // wave's step took half the elastic and Poisson iterations for the same load to 1e-5)
    const int status =
        coupled_solve(O, report, std::max(1.0, PLASTIC_LOOSEN * change / (1e2 * O.tol)));
    if (status != OK) return status;
  }
}

template <int D>
void State<D>::set_plate(int axis, int side, double force) {
  if (axis < 0 || axis >= D || (side != -1 && side != 1))
    throw std::invalid_argument("State::set_plate: an axis of the grid and a side of -1 or 1");
  const index_t nn = grid_.nnodes, npairs = T_.wall_node.size();
  plate_ = Plate{true, axis, force, 0.0, {}};
  for (index_t e = 0; e < npairs; ++e)
    if (T_.wall_axis(e) == axis && T_.wall_sign(e) * side > 0.0) plate_.pairs.push_back(e);
  if (plate_.pairs.empty())
    throw std::invalid_argument("State::set_plate: no wall on that side (an outlet, or periodic)");
  auto held = plate_held_.sized(nn * D);
  for (index_t j = 0; j < nn * D; ++j)
    held[j] = T_.wall_velocity.size() > 0 ? T_.wall_velocity.data()[j] : 0.0;
  auto bonded = plate_bonded_.sized(npairs);
  for (index_t e = 0; e < npairs; ++e) bonded[e] = T_.wall_bonded.size() > 0 && T_.wall_bonded(e);
  for (index_t e : plate_.pairs) bonded[e] = true;
  T_.wall_velocity = View<const double, 2>(held.data(), {nn, D});
  T_.wall_bonded = View<const bool>(bonded.data(), {npairs});
}

template <int D>
void State<D>::set_plate_velocity(double v) {
  plate_.velocity = v;
  if (plate_.on) hold_plate(v);  // the walls' held velocity too: the next predictor's
}

template <int D>
void State<D>::hold_plate(double velocity) {
  double* held = plate_held_.view(grid_.nnodes * D).data();
  for (index_t e : plate_.pairs) held[T_.wall_node(e) * D + plate_.axis] = velocity;
}

template <int D>
double State<D>::plate_reaction(const Options<D>& O) {
  // the force the plate's holds take: M_i / dt (x_i - v0_i) + (K x)_i - (the cells' pressure
  // force)_i along its axis at each of its nodes, x the coupled solve's velocity
  const index_t nn = grid_.nnodes, nc = grid_.ncells;
  auto x = cp_x_.template view<2>({nn, D});
  auto v0 = cp_v0_.template view<2>({nn, D});
  auto mass = node_mass_.view(nn);
  auto f = pl_f_.template sized<2>({nn, D});
  for (index_t j = 0; j < nn * D; ++j) f.data()[j] = 0.0;
  add_cell_forces<D>(grid_, pc_row_.view(nc), pc_G_.template view<3>({npc_, NC, D}),
                     p_cell_.view(nc), f);
  const double grad_div = grad_div_ratio(O.model, O.model_params.data());
  const int k = plate_.axis;
  double reaction = 0.0;
  for (index_t e : plate_.pairs) {
    const index_t i = T_.wall_node(e);
    if (!(mass(i) > 0.0)) continue;
    reaction += mass(i) / O.dt * (x(i, k) - v0(i, k)) +
                operator_force<D>(grid_, T_.viscous_T, eta_weight_.view(nc), grad_div,
                                  View<const double, 2>(x.data(), {nn, D}), i, k) -
                f(i, k);
  }
  return reaction;
}

template <int D>
int State<D>::plate_solve(const Options<D>& O, Report& report) {
  // the coupled solve is affine in the plate's velocity (the contacts fixed by the split
  // step): solved at two velocities, the two solutions combined at the one whose reaction
  // is the plate's force
  const index_t nn = grid_.nnodes, nc = grid_.ncells;
  const double va = plate_.velocity;
  hold_plate(va);
  int status = cell_pressure_solve(O, report);
  if (status == OK) status = coupled_solve(O, report);
  if (status != OK) return status;
  const double ra = plate_reaction(O);
  auto p_a = pl_p_.sized(nc), v_a = pl_v_.sized(nn * D), n_a = pl_n_.sized(nn);
  auto p_cell = p_cell_.view(nc), p_node = p_node_.view(nn);
  auto v_star = v_star_.view(nn * D);
  std::copy(p_cell.data(), p_cell.data() + nc, p_a.data());
  std::copy(v_star.data(), v_star.data() + nn * D, v_a.data());
  std::copy(p_node.data(), p_node.data() + nn, n_a.data());
  // the second velocity: the step's velocity change the force would give the plate's mass
  double mass = 0.0;
  for (index_t e : plate_.pairs) mass += node_mass_.view(nn)(T_.wall_node(e));
  double dv = std::abs(va);
  if (dv == 0.0 && mass > 0.0) dv = std::abs(plate_.force - ra) * O.dt / mass;
  if (dv == 0.0) dv = 1.0;
  hold_plate(va + dv);
  status = coupled_solve(O, report);
  if (status != OK) return status;
  const double rb = plate_reaction(O);
  if (!(std::abs(rb - ra) > 0.0))
    throw std::runtime_error(
        "State: the plate's reaction does not change with its velocity "
        "(no material under it)");
  const double w = (plate_.force - ra) / (rb - ra);
  for (index_t c = 0; c < nc; ++c) p_cell(c) = p_a(c) + w * (p_cell(c) - p_a(c));
  for (index_t j = 0; j < nn * D; ++j) v_star(j) = v_a(j) + w * (v_star(j) - v_a(j));
  for (index_t i = 0; i < nn; ++i) p_node(i) = n_a(i) + w * (p_node(i) - n_a(i));
  plate_.velocity = va + w * dv;
  hold_plate(plate_.velocity);
  return OK;
}

template <int D>
int State<D>::pressure_solve(const Options<D>& O, Report& report) {
  if (O.cell_pressure) {
    if (plate_.on) {
      if (!(O.coupled && O.viscous))
        throw std::logic_error("State: a plate takes a saturated soil's coupled step");
      return plate_solve(O, report);
    }
    const int status = cell_pressure_solve(O, report);
    return status == OK && O.coupled && O.viscous ? coupled_solve(O, report) : status;
  }
  warm_start();
  bool anchored = pressure_matrix(O);
  report.pockets += npockets_;
  const index_t n = nrows_;
  const bool shared = exchange_->shared();
  if (shared) {  // the whole system's unknowns, and whether any of them meets a free surface
    if (!solver_)
      throw std::logic_error("State: a rank's pressure step needs a solver over the ranks");
    if (exchange_->sum(owned_rows()) == 0) return OK;
    const auto owned = exchange_->owned_nodes();
    auto air = anchored_.view(n);
    auto rows = rows_.view(n);
    index_t mine = 0;
    for (index_t r = 0; r < n; ++r) mine += air(r) && (owned.size() == 0 || owned(rows(r)));
    anchored = exchange_->sum(mine) > 0;
  } else if (n == 0) {
    return OK;
  }
  if (!anchored) return SINGULAR;
  const auto [dims, period] = mg_shape(true);
  auto cols = cols_.template view<2>({n, NS});
  auto vals = vals_.template view<2>({n, NS});
  auto rows = rows_.view(n);
  const auto setup = [&] {  // the solver for the matrix as it is in vals
    if (solver_)
      solver_->setup(cols, vals, rows);
    else
      pressure_mg_.setup(cols, vals, rows, dims, COARSEST, period);
  };
  auto x = x_.view(n);
  auto rhs = rhs_.view(n);
  index_t step_iterations = 0;
  // one solve of the pressure matrix, counted; false: it did not converge (reported)
  auto solve = [&](View<const double> b, View<double> y) {
    return counted_solve(O, report, cols, vals, rows, b, y, scratch_.view(n), step_iterations,
                         false);
  };
  const bool free = bodies_.free_dofs() > 0;
  // The contact as a complementarity problem (complementarity.hpp): p >= 0 at the rows of
  // the nodes in contact, solved by rounds of the active set, each a solve with the held
  // rows at p = 0; the rounds end when no row changes (the same round on every rank).
  const index_t nn = grid_.nnodes;
  auto node_row = node_row_.view(nn);
  auto candidate = candidate_.sized(n);
  auto zero = zero_.sized(n);
  auto b = b_.sized(n);
  auto vals0 = vals0_.template sized<2>({n, NS});
  contact_rows(T_.wall_node, T_.wall_axis, T_.wall_bonded, contact_.template view<2>({nn, D}),
               ob_.onode, ocontact_.view(nn), node_row, candidate);
  std::copy(vals.data(), vals.data() + n * NS, vals0.data());
  // The rounds start from the rows held at the last step: their pressure, x's start, is
  // -0.0 (below). The held set changes little from step to step, and any start gives the
  // same solution: this one saves rounds (the dam break at 0.008 m: 1.7 solves a step at
  // dt = 1 ms, 1.5 at 0.1 ms, against 2.2 and 3.0 from none held).
  bool holding = false;  // vals differs from vals0 (a row is held)
  for (index_t r = 0; r < n; ++r) {
    zero(r) = candidate(r) && x(r) == 0.0 && std::signbit(x(r));
    holding = holding || zero(r);
  }
  if (holding) hold_at_zero(cols, vals0, zero, vals);
  setup();
  const auto owned = exchange_->owned_nodes();
  for (int round = 1;; ++round) {
    if (free) {  // the right-hand side at the free bodies' velocities before the pressure
      bodies_.reset_velocity();
      bodies_.hold(time_ + 0.5 * O.dt);
    }
    if (round == 1 || free) {  // without free bodies the right-hand side stays
      pressure_rhs(O);
      std::copy(rhs.data(), rhs.data() + n, b.data());
    }
    for (index_t r = 0; r < n; ++r) rhs(r) = zero(r) ? 0.0 : b(r);
    if (!solve(rhs, x)) return PRESSURE_NOT_CONVERGED;
    if (free) {  // w at the bodies' velocities after the pressure's impulse
      if (!couple_bodies(O, solve)) return PRESSURE_NOT_CONVERGED;
      pressure_rhs(O);
      std::copy(rhs.data(), rhs.data() + n, b.data());
    }
    double bmax = 0.0, xmax = 0.0;  // the solve's error in x and in A x - b, about tol times
    for (index_t r = 0; r < n; ++r) {
      bmax = std::max(bmax, std::abs(b(r)));
      xmax = std::max(xmax, std::abs(x(r)));
    }
    const double x_tolerance = O.tol * exchange_->max(xmax);  // collective: one order
    const double w_tolerance = O.tol * exchange_->max(bmax);
    auto next = next_.sized(n);
    index_t changed = update_active_set(cols, vals0, x, b, candidate, rows, owned, x_tolerance,
                                        w_tolerance, zero, next);
    if (shared) changed = exchange_->sum(changed);
    if (changed == 0) break;
    if (round == MAX_CONTACT_ROUNDS) {  // reported; the last round's pressure stands
      report.unsettled += 1;
      break;
    }
    std::copy(next.data(), next.data() + n, zero.data());
    if (shared) {  // the owners' held rows at the rows a rank holds without owning them
      auto flag = zero_node_.template sized<2>({nn, 1});
      for (index_t r = 0; r < n; ++r) flag(rows(r), 0) = zero(r) ? 1.0 : 0.0;
      const View<double, 2> fields[] = {flag};
      exchange_->fill_nodes(fields, 1);
      for (index_t r = 0; r < n; ++r) zero(r) = flag(rows(r), 0) > 0.5;
    }
    // the multigrid reads its finest level again (refresh), and the coarse levels of the
    // matrix the rounds started with stay a preconditioner for it; another solver sets up
    // again
    hold_at_zero(cols, vals0, zero, vals);
    holding = true;
    if (solver_)
      setup();
    else
      pressure_mg_.refresh();
  }
  auto p = p_node_.view(nn);
  // a held row's pressure is -0.0: 0 in every use, its sign marking the hold for the next
  // step's start (kept by checkpoints, the ranks' exchanges and their gathers, which copy
  // the pressure as it is, so a restarted or split run starts its rounds alike)
  for (index_t r = 0; r < n; ++r) p(rows(r)) = zero(r) ? -0.0 : x(r);
  if (grid_.any_periodic) copy_images<D>(grid_, p);
  if (holding) std::copy(vals0.data(), vals0.data() + n * NS, vals.data());
  report.released += releases([&] {
    return release_rows(T_.wall_node, T_.wall_axis, T_.wall_bonded, ob_.onode, node_row, zero,
                        contact_.template view<2>({nn, D}), ocontact_.view(nn));
  });
  report.max_iterations = std::max(report.max_iterations, step_iterations);
  extend_pressure(O);
  if (shared) {
    const View<double, 2> p[] = {p_node_.template view<2>({grid_.nnodes, 1})};
    exchange_->fill_nodes(p, 1);
  }
  return OK;
}

template <int D>
void State<D>::viscous_start(const Options<D>& O, Report& report) {
  vis_n_ = 0;
  if (!O.viscous) return;
  const index_t nn = grid_.nnodes, nc = grid_.ncells;
  auto v_old = v_old_.template view<2>({nn, D});
  auto v_star = v_star_.template view<2>({nn, D});
  auto p = p_node_.view(nn);
  // the walls hold here what the pressure step's contact will hold at its start (it decides
  // on the normal velocity of v*, which the viscous step leaves unchanged at wall nodes)
  auto contact = contact_.template view<2>({nn, D});
  auto ocontact = ocontact_.view(nn);
  auto node_row = node_row_.view(nn);
  start_contact(T_.wall_node, T_.wall_axis, T_.wall_sign, v_star, node_row, contact,
                T_.wall_bonded);
  start_obstacles(ob_.onode, ob_.onormal, v_star, node_row, ocontact, ob_.velocity);
  // the strain rate of the particles' velocity with the held nodes at rest
  auto v_rate = v_rate_.template view<2>({nn, D});
  rate_velocity<D>(v_old, T_.wall_node, T_.wall_axis, T_.wall_no_slip, contact, ob_.onode, ocontact,
                   ob_.ono_slip, v_rate, T_.wall_velocity, ob_.velocity);
  // a solid's implicit elastic predictor (plasticity.hpp): the viscous step with eta = G dt,
  // the old stress's force already in v* (scatter)
  const bool solid = is_solid(O.model);
  std::array<double, 8> elastic{};
  elastic[0] = solid ? O.model_params[0] * O.dt : 0.0;
  cell_viscosity<D>(grid_, theta_.view(nc), ob_.open, enclosed_.view(nc), O.full, v_rate, p,
                    solid ? NEWTONIAN : O.model,
                    View<const double>(solid ? elastic.data() : O.model_params.data(), {8}),
                    eta_.view(nc), eta_weight_.view(nc));
  if (solid && solid_scattered_) {
    // a yielded cell's stress no longer grows with its strain: its elastic stiffness is
    // left out of the implicit predictor (the old stress's force holds it at the yield)
    auto share = cell_yield_.view(nc);
    auto weight = eta_weight_.view(nc);
    if (O.coupled && is_plastic(O.model)) {  // the whole stiffness, for plastic_solve's secant
      auto whole = ps_weight_.sized(nc);
      std::copy(weight.data(), weight.data() + nc, whole.data());
    }
    for (index_t c = 0; c < nc; ++c) weight(c) *= 1.0 - share(c);
    if (O.model == POROELASTIC) {  // a saturated soil's free water has no skeleton
      auto water = cell_water_.view(nc);
      for (index_t c = 0; c < nc; ++c) weight(c) *= 1.0 - water(c);
    }
  }
  {
    const double cap = viscosity_cap(O.model, View<const double>(O.model_params.data(), {8}));
    auto eta = eta_.view(nc);
    auto weight = eta_weight_.view(nc);
    const auto owned = exchange_->owned_cells();  // a rank counts the cells it owns
    for (index_t c = 0; c < nc; ++c)
      if (weight(c) > 0.0 && eta(c) >= cap && (owned.size() == 0 || owned(c))) report.capped += 1;
  }
  auto base = v_c_.template view<2>({nn, D});
  if (O.cell_pressure) {
    cell_hold();
    correct_cells<D>(grid_, pc_row_.view(nc), pc_G_.template view<3>({npc_, NC, D}),
                     pc_P_.template view<3>({nn, D, D}), pc_vol_.view(nn), p_cell_.view(nc), v_star,
                     O.dt / O.rho, base);
    // what the walls and obstacles hold at their own velocity: the projector left v* there,
    // which the solve would keep at a slip wall's held normal (and the stress would read)
    apply_walls(T_.wall_node, T_.wall_axis, T_.wall_sign, T_.wall_no_slip, base, contact,
                T_.wall_velocity);
    apply_obstacles(ob_.onode, ob_.onormal, ob_.ono_slip, base, ocontact, View<const double>(),
                    ob_.velocity);
  } else {
    correct_velocity<D>(grid_, I_.cor_slot, I_.cor_C, I_.cor_V, p, v_star, O.dt / O.rho, base);
  }
}

template <int D>
index_t State<D>::viscous_system(const Options<D>& O) {
  vis_n_ = 0;
  if (!O.viscous) return 0;
  const index_t nn = grid_.nnodes, nc = grid_.ncells;
  auto contact = contact_.template view<2>({nn, D});
  auto ocontact = ocontact_.view(nn);
  auto base = v_c_.template view<2>({nn, D});
  auto vu = vu_.template view<2>({nn, D});
  auto vrow = vrow_.template view<2>({nn, D});
  auto voff = voff_.view(D + 1);
  // (the coupled solve's linear part holds its components at 0: held_still_)
  const index_t n =
      number_unknowns<D>(node_mass_.view(nn), T_.wall_node, T_.wall_axis, T_.wall_no_slip, contact,
                         ob_.onode, ocontact, ob_.ono_slip, base, vu, vrow, voff, &grid_,
                         held_still_ ? View<const double, 2>() : T_.wall_velocity,
                         held_still_ ? View<const double, 2>() : ob_.velocity);
  if (n == 0) return 0;
  auto cols = vcols_.template sized<3>({D, n, NS});
  auto vals = vvals_.template sized<3>({D, n, NS});
  auto rhs = vrhs_.sized(n);
  auto node = vnode_.sized(n);
  // a saturated soil's skeleton: its bulk stiffness beside the shear's (plasticity.hpp)
  const double grad_div = grad_div_ratio(O.model, O.model_params.data());
  mpmflow::assemble<D>(grid_, T_.viscous_T, eta_weight_.view(nc), node_mass_.view(nn), O.dt, vu,
                       vrow, voff, cols, vals, rhs, node, grad_div);
  auto x = vx_.sized(n);
  for (index_t i = 0; i < nn; ++i)
    for (int k = 0; k < D; ++k)
      if (vrow(i, k) >= 0) x(vrow(i, k)) = vu(i, k);
  vis_n_ = n;
  return n;
}

template <int D>
int State<D>::viscous_predictor(const Options<D>& O, Report& report) {
  if (O.cell_pressure && O.viscous) {
    // a solid's first step (no cell pressure yet): the pressure that answers v* before the
    // elastic step starts it, as the incompressible material's instant response to its
    // load; from 0 the elastic solve met the whole load and stored a stress the pressure
    // then took over (a column at rest kept 250 Pa of it)
    auto p_cell = p_cell_.view(grid_.ncells);
    bool zero = true;
    for (index_t c = 0; c < grid_.ncells && zero; ++c) zero = p_cell(c) == 0.0;
    // (the ranks decide together: the solve is theirs; a rank without material holds zeros)
    if (exchange_->shared()) zero = exchange_->sum(zero ? 0 : 1) == 0;
    if (zero) {
      const int status = cell_pressure_solve(O, report);
      if (status != OK) return status;
    }
  }
  viscous_start(O, report);
  if (!O.viscous) return OK;
  const index_t nn = grid_.nnodes;
  if (O.coupled) {  // v* before the elastic increment, for the coupled solve
    auto v_star = v_star_.template view<2>({nn, D});
    auto v0 = cp_v0_.template sized<2>({nn, D});
    std::copy(v_star.data(), v_star.data() + nn * D, v0.data());
  }
  if (exchange_->shared()) {
    // the corrector at the nodes on a rank's edge reaches past its cells: the owners' values
    const View<double, 2> base[] = {v_c_.template view<2>({nn, D})};
    exchange_->fill_nodes(base, 1);
  }
  const index_t n = viscous_system(O);
  if (viscous_solver_) {  // a rank's: over the ranks, whether it has unknowns or not
    auto x = vx_.view(n);
    const SolveResult res = viscous_solver_->solve(x);
    report.viscous_iterations += res.iterations;
    if (!(res.residual <= O.tol)) {
      report.fail_iterations = res.iterations;
      report.fail_residual = res.residual;
      report.fail_size = n;
      return VISCOUS_NOT_CONVERGED;
    }
    viscous_apply(x);
    const View<double, 2> v[] = {v_star_.template view<2>({nn, D})};
    exchange_->fill_nodes(v, 1);
    return OK;
  }
  if (n == 0) return OK;
  if (!viscous_solve(O, report, n)) return VISCOUS_NOT_CONVERGED;
  viscous_apply(vx_.view(n));
  return OK;
}

template <int D>
bool State<D>::viscous_solve(const Options<D>& O, Report& report, index_t n) {
  auto cols = vcols_.template view<3>({D, n, NS});
  auto vals = vvals_.template view<3>({D, n, NS});
  auto rhs = vrhs_.view(n);
  auto node = vnode_.view(n);
  auto voff = voff_.view(D + 1);
  auto x = vx_.view(n);
  auto work = vwork_.template sized<2>({5, n});
  const SolveResult res = mpmflow::solve<D>(grid_, cols, vals, node, voff, rhs, x, O.tol,
                                            O.max_iterations, O.sweeps, viscous_mg_, work);
  report.viscous_iterations += res.iterations;
  if (res.residual <= O.tol) return true;
  report.fail_iterations = res.iterations;
  report.fail_residual = res.residual;
  report.fail_node = node(mpmflow::worst_row(cols, vals, voff, x, rhs, work.row(0), work.row(1)));
  report.fail_size = n;
  return false;
}

template <int D>
void State<D>::viscous_apply(View<const double> x) {
  if (x.size() != vis_n_)
    throw std::invalid_argument(
        "State::viscous_apply: x must hold one value per unknown of the "
        "last viscous_system");
  if (vis_n_ == 0) return;
  const index_t nn = grid_.nnodes;
  auto v_star = v_star_.template view<2>({nn, D});
  auto base = v_c_.template view<2>({nn, D});
  auto vu = vu_.template view<2>({nn, D});
  auto vrow = vrow_.template view<2>({nn, D});
  for (index_t i = 0; i < nn; ++i)
    for (int k = 0; k < D; ++k) {
      const index_t r = vrow(i, k);
      v_star(i, k) += (r >= 0 ? x(r) : vu(i, k)) - base(i, k);
    }
}

template <int D>
index_t State<D>::volume_system(const Options<D>& O) {
  if (!volume_on_)
    throw std::logic_error("State::volume_system: a State built without the volume correction");
  PhaseClock clock(phase_seconds_);
  const index_t nn = grid_.nnodes, nc = grid_.ncells;
  const double inv = 1.0 / cell_volume_;
  auto density = density_.view(nc);
  auto cell_vol = cell_vol_.view(nc);
  for (index_t c = 0; c < nc; ++c) density(c) = cell_vol(c) * inv;
  auto cell_row = cell_row_.view(nc);
  auto all_cols = vol_cols_.template view<2>({nc, NS});
  auto all_vals = vol_vals_.template view<2>({nc, NS});
  const VolumeSystem assembled = mpmflow::assemble<D>(
      grid_, theta_.view(nc), density, HALF_FULL, contact_.template view<2>({nn, D}),
      ob_.static_slot, cell_row, all_cols, all_vals, vol_rhs_.view(nc), vol_rows_.view(nc));
  const index_t n = vol_n_ = assembled.n;
  vol_anchored_ = assembled.anchored;
  auto cols = vol_cols_.template view<2>({n, NS});
  auto vals = vol_vals_.template view<2>({n, NS});
  auto rhs = vol_rhs_.view(n);
  // A row touches air where its diagonal (every face with flux) exceeds its couplings to
  // other rows: unit couplings, so the sum of its values is 0 or a whole number. Taken before
  // the pockets below change the held rows' values.
  auto air = vol_air_.view(n);
  for (index_t r = 0; r < n; ++r) {
    double sum = 0.0;
    for (int s = 0; s < NS; ++s) sum += vals(r, s);
    air(r) = sum > 0.5;
  }
  if (n > 0 && vol_anchored_ && O.pockets) {
    // water sealed off from every empty cell (src/core/pockets.hpp) keeps its volume: only
    // its mean-free excess is moved about within it
    auto part = vol_part_.sized(n);
    auto anchors = vol_anchors_.sized(n);
    const index_t pockets = find_pockets(
        cols, vals, [&](index_t r) { return air(r); }, [](index_t) { return 0.0; }, part,
        vol_order_.sized(n), anchors);
    if (pockets > 0) {
      auto mean = vol_mean_.sized(2 * pockets);
      apply_pockets(part, anchors.head(pockets), mean.head(pockets),
                    View<double>(mean.data() + pockets, {pockets}), rhs);
    }
  }
  clock.lap(PHASE_VOLUME);
  return n;
}

template <int D>
index_t State<D>::volume_apply(const Options<D>& O, View<const double> q) {
  if (!volume_on_)
    throw std::logic_error("State::volume_apply: a State built without the volume correction");
  PhaseClock clock(phase_seconds_);
  const index_t nc = grid_.ncells;
  const index_t n = vol_n_;
  std::array<View<double>, D> faces;
  for (int k = 0; k < D; ++k) faces[k] = faces_[k].view(faces_[k].capacity());
  if (n == 0 || !vol_anchored_) {
    // nothing, or material filling the whole domain: its volume cannot change
    for (int k = 0; k < D; ++k)
      for (index_t i = 0; i < faces[k].size(); ++i) faces[k](i) = 0.0;
    clock.lap(PHASE_VOLUME);
    return 0;
  }
  if (q.size() != n)
    throw std::invalid_argument("State::volume_apply: q needs one value per row of the volume " +
                                std::string("system, ") + std::to_string(n) + ", not " +
                                std::to_string(q.size()));
  auto rows = vol_rows_.view(n);
  auto Q = q_.view(nc);
  for (index_t c = 0; c < nc; ++c) Q(c) = 0.0;
  for (index_t r = 0; r < n; ++r) Q(rows(r)) = q(r);
  const double dmax = O.volume_dmax * grid_.h;
  face_displacements<D>(grid_, cell_row_.view(nc), ob_.static_slot, q, O.volume_rate * grid_.h,
                        dmax, faces);
  index_t clamped = 0;
  for (int k = 0; k < D; ++k)
    for (index_t i = 0; i < faces[k].size(); ++i)
      if (std::abs(faces[k](i)) >= dmax) clamped += 1;
  clock.lap(PHASE_VOLUME);
  return clamped;
}

template <int D>
int State<D>::volume_correction(const Options<D>& O, Report& report) {
  const index_t n = volume_system(O);
  auto q = qx_.view(n);
  bool solve = n > 0 && vol_anchored_;
  if (exchange_->shared()) {  // the whole system's rows, and whether any touches air
    const auto owned = exchange_->owned_cells();
    auto rows = vol_rows_.view(n);
    auto air = vol_air_.view(n);
    index_t mine = 0, wet = 0;
    for (index_t r = 0; r < n; ++r) {
      const bool own = owned.size() == 0 || owned(rows(r));
      mine += own ? 1 : 0;
      wet += own && air(r) ? 1 : 0;
    }
    vol_anchored_ = exchange_->sum(wet) > 0;
    solve = exchange_->sum(mine) > 0 && vol_anchored_;
    if (!solve) vol_anchored_ = false;  // nothing to move: volume_apply zeroes the faces
    if (solve && !volume_solver_)
      throw std::logic_error("State: a rank's volume correction needs a solver over the ranks");
  }
  if (solve) {
    PhaseClock clock(phase_seconds_);
    const index_t nc = grid_.ncells;
    auto rows = vol_rows_.view(n);
    auto cols = vol_cols_.template view<2>({n, NS});
    auto vals = vol_vals_.template view<2>({n, NS});
    auto rhs = vol_rhs_.view(n);
    auto Q = q_.view(nc);
    for (index_t r = 0; r < n; ++r) q(r) = Q(rows(r));  // the last correction's solution
    const auto [dims, period] = mg_shape(false);
    SolveResult res;
    if (volume_solver_) {
      volume_solver_->setup(cols, vals, rows);
      res = volume_solver_->solve(rhs, q);
    } else {
      volume_mg_.setup(cols, vals, rows, dims, COARSEST, period);
      res = volume_mg_.pcg(rhs, q, O.volume_tol, O.volume_max_iterations, 1);
    }
    report.volume_iterations += res.iterations;
    clock.lap(PHASE_VOLUME);
    if (!(res.residual <= O.volume_tol)) {
      report.fail_iterations = res.iterations;
      report.fail_residual = res.residual;
      report.fail_node = rows(worst_row(cols, vals, q, rhs, scratch_.sized(n)));
      report.fail_size = n;
      return VOLUME_NOT_CONVERGED;
    }
  }
  report.clamped += volume_apply(O, q);
  return OK;
}

template <int D>
int State<D>::finish(const Particles<D>& P, const Options<D>& O, bool correct, Report& report) {
  this->correct(O);
  if (correct) {  // volume_system, volume_apply and the solve time themselves
    const int status = volume_correction(O, report);
    if (status != OK) return status;
  }
  // a rank moves its own particles, not the halo
  report.moved += to_particles(P, O, correct, exchange_->owned(P));
  return OK;
}

template <int D>
void State<D>::correct(const Options<D>& O) {
  const index_t nn = grid_.nnodes;
  PhaseClock clock(phase_seconds_);
  auto v_new = v_new_.template view<2>({nn, D});
  auto contact = contact_.template view<2>({nn, D});
  auto ocontact = ocontact_.view(nn);
  if (O.cell_pressure) {  // the contacts' projector as the pressure step left them
    const index_t nc = grid_.ncells;
    correct_cells<D>(grid_, pc_row_.view(nc), pc_G_.template view<3>({npc_, NC, D}),
                     pc_P_.template view<3>({nn, D, D}), pc_vol_.view(nn), p_cell_.view(nc),
                     v_star_.template view<2>({nn, D}), O.dt / O.rho, v_new);
  } else {
    correct_velocity<D>(grid_, I_.cor_slot, I_.cor_C, I_.cor_V, p_node_.view(nn),
                        v_star_.template view<2>({nn, D}), O.dt / O.rho, v_new);
  }
  apply_walls(T_.wall_node, T_.wall_axis, T_.wall_sign, T_.wall_no_slip, v_new, contact,
              T_.wall_velocity);
  // with the face term (wall_flux) only the obstacle nodes in the solid: the corrected
  // velocity of a node in the water already meets the face's condition (weakly, at the
  // face); zeroing its normal velocity held the water up to a cell short of the face, where
  // the cut cell's fluid part then stayed empty and its solid-side node fell out of the
  // pressure system (p = 0 at the face; SPHERIC Test 2 at 0.02 m, docs/notes/benchmarks-diary.md).
  // The paper's formulation constrains v* at every obstacle node, and so its result.
  apply_obstacles(ob_.onode, ob_.onormal, ob_.ono_slip, v_new, ocontact,
                  O.wall_flux ? ob_.phi : View<const double>(), ob_.velocity);
  clock.lap(PHASE_CORRECTOR);
}

template <int D>
index_t State<D>::to_particles(const Particles<D>& all, const Options<D>& O, bool displaced,
                               index_t owned) {
  // The first `owned` particles move (a rank's own; the rest, its halo, are its neighbours'
  // copies). Only the particles' own arrays and the grid's are read (grid_to_particles,
  // push_out and update_stresses use no binning array: cell_, order_, start_) but for a
  // solid's tools' reactions, which read the stress of every particle round a node
  // (stress_forces, through scatter's binning): on a rank the halo then takes its owners'
  // new stress first, the one place it is computed (with its old stress, a footing across the
  // ranks' cut read 207 N of 49 kN wrong).
  const Particles<D> P = owned < 0 ? all : all.head(std::min(owned, all.count()));
  const index_t nn = grid_.nnodes;
  PhaseClock clock(phase_seconds_);
  if (P.stress.size() > 0 && is_solid(O.model)) {
    // the stress from the corrected grid velocity, the field the particles move with, at the
    // positions the step started from (update-stress-last); the particles' velocities mapped
    // back to the grid first (modified USL) were smoother than the motion, so the stress
    // fell behind the strain: a cantilever damped by PIC transfers came to rest 34% deeper
    // than its static deflection at h = H / 4, and within 1% of it from this velocity
    update_stresses<D>(grid_, P.x, P.mass, P.volume, v_new_.template view<2>({nn, D}),
                       p_node_.view(nn), O.dt, O.model,
                       View<const double>(O.model_params.data(), {8}), P.stress, P.plastic_strain,
                       P.yielding);
    if (bodies_.present()) {
      // the material's force on its tools: at each node a tool holds, the force the node
      // needs beyond its stress's (the deviatoric stress just updated, the cells' pressure)
      // and its weight to change its momentum as it did, r_i = M_i ((v_new - v_old) / dt -
      // g) - f_i, summed over the tool's nodes (the discrete reaction: pressure, shear and
      // the inertia of the material the tool carries; the fluids' cut-cell pressure
      // integral below would see the pressure only)
      if (all.count() != binned_)
        throw std::logic_error("to_particles: a solid's tools need the particles scattered");
      if (exchange_->shared()) exchange_->refresh_halo();
      const index_t nc = grid_.ncells;
      auto f = force_.template view<2>({nn, D});
      stress_forces<D>(grid_, all.x, all.volume, all.stress, order_.view(all.count()),
                       start_.view(nc + 1), f);
      add_cell_forces<D>(grid_, pc_row_.view(nc), pc_G_.template view<3>({npc_, NC, D}),
                         p_cell_.view(nc), f);
      auto m = node_mass_.view(nn);
      auto v_old = v_old_.template view<2>({nn, D});
      auto v_new = v_new_.template view<2>({nn, D});
      parallel_for(nn, [&](index_t i) {
        for (int k = 0; k < D; ++k)
          f(i, k) = m(i) * ((v_new(i, k) - v_old(i, k)) / O.dt - O.gravity[k]) - f(i, k);
      });
      // (on a rank: the nodes it owns, summed over the ranks below)
      bodies_.reactions(f, ocontact_.view(nn), body_force_.template view<2>({bodies_.count(), D}),
                        body_torque_.template view<2>({bodies_.count(), 3}),
                        exchange_->owned_nodes());
    }
    // a held component's increment is 0 (its velocity is set, not accelerated: MPM's boundary
    // condition on the acceleration; exact for walls at rest or at a steady speed): the
    // increment v_new - v_old there, with v_old the particles' own velocity, slowed the
    // particles beside a bonded floor every step (a clay layer sliding on it: its lowest
    // particles moved upslope)
    auto v_old = v_old_.template view<2>({nn, D});
    apply_walls(T_.wall_node, T_.wall_axis, T_.wall_sign, T_.wall_no_slip, v_old,
                contact_.template view<2>({nn, D}), T_.wall_velocity);
    // (not at a tool's nodes: it holds the nodes within a cell of its face, where the
    // particles it has just taken along must take its velocity; with the increment 0 they
    // kept their own, carried it out of the held cells, and a footing blew up in 20 steps)
    if (!bodies_.present())
      apply_obstacles(ob_.onode, ob_.onormal, ob_.ono_slip, v_old, ocontact_.view(nn),
                      View<const double>(), ob_.velocity);
  }
  std::array<View<const double>, D> faces{};  // empty: no displacement
  if (displaced)
    for (int k = 0; k < D; ++k) faces[k] = faces_[k].view(faces_[k].capacity());
  index_t moved = grid_to_particles<D>(
      grid_, P.x, P.v, P.pressure, v_old_.template view<2>({nn, D}),
      v_new_.template view<2>({nn, D}), p_node_.view(nn), O.dt, O.flip,
      View<const double>(lower_.data(), {D}), View<const double>(upper_.data(), {D}), margin_,
      faces, P.affine, Outlets{T_.outlet, P.mass, P.volume, T_.inlets.count() > 0});
  if (bodies_.present()) {   // the bodies' force of this step, then the bodies at its end
    if (!is_solid(O.model))  // a solid's: its reactions, above (on a rank: its cut cells)
      bodies_.forces(p_node_.view(nn), body_force_.template view<2>({bodies_.count(), D}),
                     body_torque_.template view<2>({bodies_.count(), 3}), exchange_->owned_cells());
    if (exchange_->shared()) {  // each rank's share, summed over the ranks
      exchange_->sum_values(body_force_.view(bodies_.count() * D));
      exchange_->sum_values(body_torque_.view(bodies_.count() * 3));
    }
    bodies_.integrate(O.dt, time_ + O.dt, exchange_);  // the free bodies' new poses
    bodies_.place(time_ + O.dt);
    bodies_.hold(time_ + O.dt);
    ob_ = bodies_.tables();
    // the last step's obstacle contacts belong to its obstacle nodes
    auto ocontact = ocontact_.view(nn);
    for (index_t i = 0; i < nn; ++i) ocontact(i) = false;
  }
  if (obstacles_) {
    moved += push_out<D>(grid_, P.x, P.v, ob_.phi, margin_, ob_.velocity);
    // a particle pushed out of an obstacle near a periodic end may cross it
    if (grid_.any_periodic)
      parallel_for(P.count(), [&](index_t p) { wrap_periodic<D>(grid_, P.x, p); });
  }
  clock.lap(PHASE_G2P);
  return moved;
}

template <int D>
int State<D>::step_once(const Particles<D>& P, const Options<D>& O, bool correct, Report& report) {
  if (bodies_.present()) {  // the bodies' mean velocity (a free body's before the pressure)
    bodies_.predict(O.dt, O.gravity);
    bodies_.hold(time_ + 0.5 * O.dt);
  }
  predict(P, O, correct);
  // the unknowns of the whole system (a rank's rows round its box are its owners')
  const index_t n = exchange_->shared()
                        ? exchange_->sum(O.cell_pressure ? owned_cell_rows() : owned_rows())
                        : (O.cell_pressure ? npc_ : nrows_);
  report.unknowns = std::max(report.unknowns, n);
  report.last_unknowns = n;
  PhaseClock clock(phase_seconds_);
  int status = viscous_predictor(O, report);
  if (T_.damping.size() > 0)  // the damping zones (sponges.hpp)
    damp_velocity<D>(T_.damping, node_mass_.view(grid_.nnodes), O.gravity, O.dt,
                     v_star_.template view<2>({grid_.nnodes, D}));
  clock.lap(PHASE_VISCOUS);
  if (status == OK) status = pressure_solve(O, report);
  if (status == OK && O.coupled && O.viscous && is_plastic(O.model) && solid_scattered_)
    status = plastic_solve(P, O, report);
  clock.lap(PHASE_PRESSURE);
  if (status == OK) status = finish(P, O, correct, report);
  if (status == OK && T_.inlets.count() > 0)
    emit_layers<D>(T_.inlets, O.dt, inlet_travel(), pool_, P.x, P.v, P.mass, P.volume, P.pressure,
                   P.affine);
  if (status == OK) {
    exchange_->migrate();  // a rank's particles to the ranks that own their new cells
    time_ += O.dt;
    report.steps += 1;
    report.dt_min = report.steps == 1 ? O.dt : std::min(report.dt_min, O.dt);
    report.dt_max = std::max(report.dt_max, O.dt);
  }
  return status;
}

template <int D>
index_t State<D>::advance(const Particles<D>& P, const Options<D>& O, index_t first, index_t nsteps,
                          Report& report, const Between& between) {
  // a rank that stopped alone would leave the others waiting: ranks stop at chunk ends
  const bool check = between && !exchange_->shared();
  for (index_t k = 0; k < nsteps; ++k) {
    report.step = k;
    const Particles<D> L = exchange_->particles(P);
    const int status = step_once(L, O, volume_due_fixed(first + k, O.volume_every), report);
    if (status != OK) {
      report.status = status;
      return k;
    }
    if (check && k + 1 < nsteps && !between()) {
      report.status = INTERRUPTED;
      return k + 1;
    }
  }
  return nsteps;
}

template <int D>
double State<D>::advance_span(const Particles<D>& P, const Options<D>& O, double span,
                              index_t max_steps, Report& report, const Between& between) {
  double elapsed = 0.0;
  Options<D> Ok = O;
  const bool check = between && !exchange_->shared();  // as in advance
  for (index_t k = 0; k < max_steps && elapsed < span; ++k) {
    report.step = k;
    const Particles<D> L = exchange_->particles(P);
    const index_t n = L.count();
    double vmax2 = reduce_chunks<double>(
        n,
        [&](index_t lo, index_t hi) {
          double m = 0.0;
          for (index_t p = lo; p < hi; ++p) {
            double s = 0.0;
            for (int d = 0; d < D; ++d) s += L.v(p, d) * L.v(p, d);
            m = std::max(m, s);
          }
          return m;
        },
        [](double a, double b) { return std::max(a, b); });
    vmax2 = exchange_->max(vmax2);  // over every rank's particles
    // a moving body's points count as the particles do: it crosses at most courant cells
    const double body = bodies_.present() ? bodies_.max_speed(time_) : 0.0;
    vmax2 = std::max(vmax2, body * body);
    const double rest = span - elapsed;
    const double dt = adaptive_dt(vmax2, O.courant, grid_.h, O.dt_max, rest);
    Ok.dt = dt;
    Ok.flip = flip_per_step(O.flip_rate, dt);
    const bool correct = volume_due_adaptive(since_volume_, dt, O.volume_rate, O.volume_interval);
    const int status = step_once(L, Ok, correct, report);
    if (status != OK) {
      report.status = status;
      return elapsed;
    }
    elapsed = dt >= rest ? span : elapsed + dt;
    if (check && elapsed < span && !between()) {
      report.status = INTERRUPTED;
      return elapsed;
    }
  }
  return elapsed;
}

template class State<2>;
template class State<3>;

}  // namespace mpmflow
