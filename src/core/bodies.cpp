#include "bodies.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cut_cells.hpp"
#include "dense.hpp"
#include "exchange.hpp"

namespace mpmflow {

namespace {

// the rotation by angle about a unit axis (Rodrigues; 2D: about z)
template <int D>
std::array<std::array<double, D>, D> rotation(double angle, const std::array<double, 3>& a) {
  const double c = std::cos(angle), s = std::sin(angle);
  std::array<std::array<double, D>, D> R{};
  if constexpr (D == 2) {
    (void)a;
    R[0] = {c, -s};
    R[1] = {s, c};
  } else {
    const double t = 1.0 - c;
    R[0] = {c + a[0] * a[0] * t, a[0] * a[1] * t - a[2] * s, a[0] * a[2] * t + a[1] * s};
    R[1] = {a[1] * a[0] * t + a[2] * s, c + a[1] * a[1] * t, a[1] * a[2] * t - a[0] * s};
    R[2] = {a[2] * a[0] * t - a[1] * s, a[2] * a[1] * t + a[0] * s, c + a[2] * a[2] * t};
  }
  return R;
}

// cubic Hermite on [t0, t0 + w] at s in [0, 1]: value and rate from the ends' values (p) and
// rates (m)
struct Hermite {
  double h00, h10, h01, h11, d00, d10, d01, d11, w;
  Hermite(double s, double width) : w(width) {
    const double s2 = s * s, s3 = s2 * s;
    h00 = 2 * s3 - 3 * s2 + 1;
    h10 = s3 - 2 * s2 + s;
    h01 = -2 * s3 + 3 * s2;
    h11 = s3 - s2;
    d00 = 6 * s2 - 6 * s;
    d10 = 3 * s2 - 4 * s + 1;
    d01 = -6 * s2 + 6 * s;
    d11 = 3 * s2 - 2 * s;
  }
  double value(double p0, double m0, double p1, double m1) const {
    return h00 * p0 + h10 * w * m0 + h01 * p1 + h11 * w * m1;
  }
  double rate(double p0, double m0, double p1, double m1) const {
    return (d00 * p0 + d10 * w * m0 + d01 * p1 + d11 * w * m1) / w;
  }
};

}  // namespace

template <int D>
void Pose<D>::velocity_at(const double* x, double* out) const {
  double r[3] = {0.0, 0.0, 0.0};
  for (int k = 0; k < D; ++k) r[k] = x[k] - centre[k];
  const double w[3] = {omega[1] * r[2] - omega[2] * r[1], omega[2] * r[0] - omega[0] * r[2],
                       omega[0] * r[1] - omega[1] * r[0]};
  for (int k = 0; k < D; ++k) out[k] = velocity[k] + w[k];
}

namespace {
// the rotation of a unit quaternion (w, x, y, z); 2D: its upper-left block (about z)
template <int D>
std::array<std::array<double, D>, D> rotation_of(const std::array<double, 4>& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double R3[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                           {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                           {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
  std::array<std::array<double, D>, D> R{};
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) R[i][j] = R3[i][j];
  return R;
}

// a free 3D body's inertia in the grid's frame, R I R^T (R: its orientation)
std::array<std::array<double, 3>, 3> world_inertia(const std::array<std::array<double, 3>, 3>& R,
                                                   const std::array<std::array<double, 3>, 3>& I) {
  std::array<std::array<double, 3>, 3> Iw{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (int m = 0; m < 3; ++m) Iw[i][j] += R[i][k] * I[k][m] * R[j][m];
  return Iw;
}

// a x b
std::array<double, 3> cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

}  // namespace

template <int D>
Pose<D> Body<D>::pose(double t) const {
  Pose<D> q;
  if (free) {
    q.centre = centre_now;
    q.velocity = velocity_now;
    q.R = rotation_of<D>(quat);
    q.omega = omega_now;
    if constexpr (D == 2) q.omega[0] = q.omega[1] = 0.0;
    q.angle = 2.0 * std::atan2(quat[3], quat[0]);
    return q;
  }
  const index_t n = time.size();
  double a = 0.0, da = 0.0;
  if (t <= time(0) || n == 1) {
    const index_t e = t <= time(0) ? 0 : n - 1;
    for (int k = 0; k < D; ++k) {
      q.centre[k] = centre(e, k);
      q.velocity[k] = velocity(e, k);
    }
    a = angle(e);
    da = rate(e);
  } else if (t >= time(n - 1)) {
    for (int k = 0; k < D; ++k) {
      q.centre[k] = centre(n - 1, k);
      q.velocity[k] = velocity(n - 1, k);
    }
    a = angle(n - 1);
    da = rate(n - 1);
  } else {
    const double* t0 = time.data();
    const index_t j = std::upper_bound(t0, t0 + n, t) - t0 - 1;  // time(j) <= t < time(j + 1)
    const Hermite H((t - time(j)) / (time(j + 1) - time(j)), time(j + 1) - time(j));
    for (int k = 0; k < D; ++k) {
      q.centre[k] = H.value(centre(j, k), velocity(j, k), centre(j + 1, k), velocity(j + 1, k));
      q.velocity[k] = H.rate(centre(j, k), velocity(j, k), centre(j + 1, k), velocity(j + 1, k));
    }
    a = H.value(angle(j), rate(j), angle(j + 1), rate(j + 1));
    da = H.rate(angle(j), rate(j), angle(j + 1), rate(j + 1));
  }
  q.R = rotation<D>(a, axis);
  q.angle = a;
  for (int k = 0; k < 3; ++k) q.omega[k] = da * axis[k];
  return q;
}

template <int D>
double Body<D>::distance(const Pose<D>& q, const double* x) const {
  // y = R^T (x - c), then multilinear on the lattice
  std::array<double, D> u;
  std::array<index_t, D> i0;
  for (int k = 0; k < D; ++k) {
    double y = 0.0;
    for (int m = 0; m < D; ++m) y += q.R[m][k] * (x[m] - q.centre[m]);
    const double s = (y - origin[k]) / spacing;
    if (!(s >= 0.0) || s > static_cast<double>(counts[k] - 1)) return BodyTables<D>::FAR;
    i0[k] = std::min(static_cast<index_t>(s), counts[k] - 2);
    u[k] = s - static_cast<double>(i0[k]);
  }
  double value = 0.0;
  for (int a = 0; a < (1 << D); ++a) {
    index_t flat = 0, stride = 1;
    double w = 1.0;
    for (int k = 0; k < D; ++k) {
      const int bit = (a >> k) & 1;
      w *= bit ? u[k] : 1.0 - u[k];
      flat += (i0[k] + bit) * stride;
      stride *= counts[k];
    }
    value += w * phi(flat);
  }
  return value;
}

template <int D>
void BodyTables<D>::setup(const Grid<D>& g, const ObstacleTables<D>& fixed,
                          View<const bool> fixed_no_slip, std::vector<Body<D>> bodies,
                          index_t nsub) {
  g_ = g;
  for (int k = 0; k < D; ++k) {
    origin_[k] = 0;
    domain_[k] = g.cells[k];
  }
  fixed_ = fixed;
  fixed_no_slip_ = fixed_no_slip;
  bodies_ = std::move(bodies);
  poses_.assign(bodies_.size(), Pose<D>{});
  held_.assign(bodies_.size(), Pose<D>{});
  nsub_ = nsub;
  nfixed_ = fixed.K.extent(0);
  nslots_ = nfixed_;
  placed_ = false;
  const index_t nn = g.nnodes, nc = g.ncells;
  for (const Body<D>& b : bodies_)
    for (int k = 0; k < D; ++k)
      if (b.counts[k] < 2 || !(b.spacing > 0.0) || b.phi.size() == 0)
        throw std::invalid_argument("BodyTables: a body's lattice needs 2 points per axis");
  auto phi = phi_.sized(nn);
  auto owner = owner_.sized(nn);
  auto vel = velocity_.sized(nn * D);
  for (index_t i = 0; i < nn; ++i) {
    phi(i) = fixed.phi.size() > 0 ? fixed.phi(i) : FAR;
    owner(i) = -1;
  }
  for (index_t i = 0; i < nn * D; ++i) vel(i) = 0.0;
  auto open = open_.sized(nc);
  auto slot = slot_.sized(nc);
  for (index_t c = 0; c < nc; ++c) {
    open(c) = fixed.open(c);
    slot(c) = fixed.static_slot(c);
  }
  // the fixed slots first; the bodies' after them
  auto copy = [](Buffer<double>& to, const double* from, index_t n) {
    to.reserve(n);
    std::copy(from, from + n, to.view(n).data());
  };
  copy(K_, fixed.K.data(), fixed.K.size());
  copy(C_, fixed.C.data(), fixed.C.size());
  copy(V_, fixed.V.data(), fixed.V.size());
  copy(F_, fixed.F.data(), fixed.F.size());
  copy(Wf_, fixed.Wf.data(), fixed.Wf.size());
  slot_owner_.reserve(nfixed_);
  for (index_t s = 0; s < nfixed_; ++s) slot_owner_.view(nfixed_)(s) = -1;
  nonode_ = fixed.onode.size();
  onode_.reserve(nonode_);
  onormal_.reserve(nonode_ * D);
  ono_slip_.reserve(nonode_);
  for (index_t e = 0; e < nonode_; ++e) {
    onode_.view(nonode_)(e) = fixed.onode(e);
    ono_slip_.view(nonode_)(e) = fixed.ono_slip(e);
    for (int k = 0; k < D; ++k) onormal_.view(nonode_ * D)(e * D + k) = fixed.onormal(e, k);
  }
  nvec_.reserve(nn * D);
  // the free bodies' unheld degrees of freedom
  dofs_.clear();
  dof_of_.assign(bodies_.size(), std::array<index_t, 6>{-1, -1, -1, -1, -1, -1});
  constexpr int NR = D == 2 ? 1 : 3;
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    Body<D>& body = bodies_[b];
    if (!body.free) continue;
    if (!(body.mass > 0.0))
      throw std::invalid_argument("BodyTables: a free body needs a positive mass");
    for (index_t kind = 0; kind < D + NR; ++kind)
      if (!body.locked[kind]) {
        dof_of_[b][kind] = static_cast<index_t>(dofs_.size());
        dofs_.push_back({static_cast<index_t>(b), kind});
      }
    body.velocity_star = body.velocity_now;
    body.omega_star = body.omega_now;
  }
  // contacts: each surface point against each wall, the fixed obstacles and the other bodies
  index_t most = 0;
  const index_t others = static_cast<index_t>(bodies_.size()) - 1;
  for (const Body<D>& body : bodies_)
    if (body.free) most = std::max(most, body.surface.extent(0) * (2 * D + 1 + others));
  contacts_.reserve(CONTACT * std::max<index_t>(most, 1));
  index_t points = 0;
  for (const Body<D>& body : bodies_)
    if (body.free) points = std::max(points, body.surface.extent(0));
  fixed_at_.reserve((D + 2) * std::max<index_t>(points, 1));
  contact_poses_.assign(bodies_.size(), Pose<D>{});
  inverse_inertia_.assign(bodies_.size(), {});
  const index_t nq = free_dofs();
  small_.reserve(nq * nq);
  rhs_small_.reserve(nq);
}

template <int D>
void BodyTables<D>::restore() {
  if (!placed_) return;
  auto phi = phi_.view(g_.nnodes);
  auto owner = owner_.view(g_.nnodes);
  auto vel = velocity_.template view<2>({g_.nnodes, D});
  auto open = open_.view(g_.ncells);
  auto slot = slot_.view(g_.ncells);
  for_box(0, [&](const std::array<index_t, D>& ix) {
    index_t i = 0, c = 0;
    bool cell = true;
    for (int k = 0; k < D; ++k) {
      i += ix[k] * g_.ns[k];
      if (ix[k] >= box_hi_[k])
        cell = false;
      else
        c += ix[k] * g_.cs[k];
    }
    phi(i) = fixed_.phi.size() > 0 ? fixed_.phi(i) : FAR;
    owner(i) = -1;
    for (int k = 0; k < D; ++k) vel(i, k) = 0.0;
    if (cell) {
      open(c) = fixed_.open(c);
      slot(c) = fixed_.static_slot(c);
    }
  });
}

template <int D>
index_t BodyTables<D>::corner_cell(const std::array<index_t, D>& ix, int a) const {
  index_t c = 0;
  for (int k = 0; k < D; ++k) {
    const index_t cx = ix[k] - ((a >> k) & 1);
    if (cx < 0 || cx >= g_.cells[k]) return -1;
    c += cx * g_.cs[k];
  }
  return c;
}

template <int D>
bool BodyTables<D>::staircase_node(const std::array<index_t, D>& ix, index_t i, double* normal) {
  auto phi = phi_.view(g_.nnodes);
  auto slot = slot_.view(g_.ncells);
  if (phi(i) >= REACH * g_.h) return false;
  bool open = false;  // a corner of a cell that is not solid: material may reach it
  for (int a = 0; a < NC && !open; ++a) {
    const index_t c = corner_cell(ix, a);
    open = c >= 0 && slot(c) >= 0;
  }
  if (!open) return false;
  // into the solid: -grad phi, by differences over the neighbouring nodes (one-sided at
  // the grid's ends)
  double size = 0.0;
  for (int k = 0; k < D; ++k) {
    const index_t lo = ix[k] > 0 ? i - g_.ns[k] : i;
    const index_t hi = ix[k] < g_.cells[k] ? i + g_.ns[k] : i;
    normal[k] =
        hi != lo ? -(phi(hi) - phi(lo)) / (static_cast<double>((hi - lo) / g_.ns[k]) * g_.h) : 0.0;
    size += normal[k] * normal[k];
  }
  size = std::sqrt(size);
  if (!(size > 0.0)) return false;  // a flat phi: no direction to hold
  for (int k = 0; k < D; ++k) normal[k] /= size;
  const index_t owner = owner_.view(g_.nnodes)(i);
  // in the body, or nearest a fixed obstacle (which does not move: held within REACH cells
  // of it all round)
  if (phi(i) <= 0.0 || owner < 0) return true;
  // outside a tool: held only ahead of a face that advances into the material, within
  // REACH cells along the tool's motion there (beside the face or behind it, not at all)
  double x[D], v[D];
  for (int k = 0; k < D; ++k) x[k] = at(ix[k], k);
  poses_[owner].velocity_at(x, v);
  double speed = 0.0, into = 0.0;
  for (int k = 0; k < D; ++k) {
    speed += v[k] * v[k];
    into += v[k] * normal[k];
  }
  speed = std::sqrt(speed);
  const double ahead = speed > 0.0 ? -into / speed : 0.0;
  return phi(i) < REACH * g_.h * ahead;
}

template <int D>
void BodyTables<D>::set_domain(const std::array<index_t, D>& origin,
                               const std::array<index_t, D>& cells) {
  origin_ = origin;
  domain_ = cells;
}

template <int D>
void BodyTables<D>::place(double t) {
  restore();
  const index_t nn = g_.nnodes, nc = g_.ncells;
  // the box: every body's lattice in the grid, a node more each way
  std::array<double, D> lo, hi;
  lo.fill(1e300);
  hi.fill(-1e300);
  std::vector<std::array<bool, 2 * D>> shifts(bodies_.size());
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    const Body<D>& body = bodies_[b];
    poses_[b] = body.pose(t);
    const Pose<D>& q = poses_[b];
    std::array<double, D> slo, shi;  // the shape's box in the grid
    slo.fill(1e300);
    shi.fill(-1e300);
    for (int a = 0; a < NC; ++a) {
      for (int k = 0; k < D; ++k) {
        double xl = q.centre[k], xs = q.centre[k];
        for (int m = 0; m < D; ++m) {
          const bool up = (a >> m) & 1;
          xl += q.R[k][m] * (body.origin[m] + (up ? (body.counts[m] - 1) * body.spacing : 0.0));
          xs += q.R[k][m] * (up ? body.hi[m] : body.lo[m]);
        }
        lo[k] = std::min(lo[k], xl);
        hi[k] = std::max(hi[k], xl);
        slo[k] = std::min(slo[k], xs);
        shi[k] = std::max(shi[k], xs);
      }
    }
    const double tol = 1e-9 * g_.h;
    for (int k = 0; k < D; ++k) {
      shifts[b][2 * k] = !g_.periodic[k] && slo[k] <= tol;
      shifts[b][2 * k + 1] = !g_.periodic[k] && shi[k] >= domain_[k] * g_.h - tol;
    }
  }
  for (int k = 0; k < D; ++k) {
    box_lo_[k] = std::clamp<index_t>(
        static_cast<index_t>(std::floor(lo[k] * g_.inv_h)) - 1 - origin_[k], 0, g_.cells[k]);
    box_hi_[k] = std::clamp<index_t>(
        static_cast<index_t>(std::ceil(hi[k] * g_.inv_h)) + 1 - origin_[k], 0, g_.cells[k]);
    // wholly outside (on a rank, a body beside its box): the grid's nearest plane of nodes,
    // which it does not reach
    if (box_lo_[k] > box_hi_[k]) box_lo_[k] = box_hi_[k];
  }
  placed_ = true;
  auto phi = phi_.view(nn);
  auto owner = owner_.view(nn);
  // the box's nodes: each body's distance where it is the nearest
  for_box(0, [&](const std::array<index_t, D>& ix) {
    index_t i = 0;
    for (int k = 0; k < D; ++k) i += ix[k] * g_.ns[k];
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      double x[D];
      for (int k = 0; k < D; ++k) {
        x[k] = at(ix[k], k);
        // a node on a domain wall (on a rank: the grid's edge only where the domain's is)
        if (ix[k] + origin_[k] == 0 && shifts[b][2 * k]) x[k] += g_.h;
        if (ix[k] + origin_[k] == domain_[k] && shifts[b][2 * k + 1]) x[k] -= g_.h;
      }
      double d = bodies_[b].distance(poses_[b], x);
      if (std::abs(d) <= ON_SURFACE * g_.h) d = 0.0;
      if (d < phi(i)) {
        phi(i) = d;
        owner(i) = static_cast<index_t>(b);
      }
    }
  });
  // the box's cells: solid, whole or candidates for the cut-cell integrals
  auto corner_range = [&](index_t c, double& mn, double& mx) {
    index_t cx[D];
    g_.cell_coords(c, cx);
    index_t first = 0;
    for (int k = 0; k < D; ++k) first += cx[k] * g_.ns[k];
    mn = 1e300;
    mx = -1e300;
    for (int a = 0; a < NC; ++a) {
      const double v = phi(first + g_.corner[a]);
      mn = std::min(mn, v);
      mx = std::max(mx, v);
    }
  };
  auto touching = [&](index_t c) {
    double mn, mx;
    corner_range(c, mn, mx);
    return mn <= 0.0 && mx > 0.0;
  };
  index_t ncells_box = 1;
  for (int k = 0; k < D; ++k) ncells_box *= std::max<index_t>(0, box_hi_[k] - box_lo_[k]);
  auto cand = cand_.sized(ncells_box);
  auto open = open_.view(nc);
  auto slot = slot_.view(nc);
  index_t m = 0;
  for_box(1, [&](const std::array<index_t, D>& cx) {
    index_t c = 0;
    for (int k = 0; k < D; ++k) c += cx[k] * g_.cs[k];
    double mn, mx;
    corner_range(c, mn, mx);
    if (mx <= 0.0) {
      slot(c) = -1;
      open(c) = 0.0;
      return;
    }
    slot(c) = 0;
    open(c) = 1.0;
    bool near = mn <= 0.0;
    for (int k = 0; k < D && !near; ++k) {
      if (cx[k] > 0 && touching(c - g_.cs[k])) near = true;
      if (cx[k] + 1 < g_.cells[k] && touching(c + g_.cs[k])) near = true;
    }
    if (near && nsub_ > 0) cand(m++) = c;  // the staircase (nsub 0) cuts none
  });
  // their integrals, after the fixed slots
  const index_t total = nfixed_ + m;
  auto K = K_.template sized<3>({total, NC, NC});
  auto C = C_.template sized<4>({total, NC, NC, D});
  auto V = V_.template sized<2>({total, NC});
  auto F = F_.template sized<4>({total, NC, NC, D});
  auto Wf = Wf_.template sized<4>({total, 2 * D, NC, NC});
  auto parts = parts_.sized(m);
  const index_t kk = NC * NC, cc = NC * NC * D, ww = 2 * D * NC * NC;
  cut_cell_tensors<D>(g_, View<const double>(phi.data(), {nn}),
                      View<const index_t>(cand.data(), {m}), nsub_,
                      View<double, 3>(K.data() + nfixed_ * kk, {m, NC, NC}),
                      View<double, 4>(C.data() + nfixed_ * cc, {m, NC, NC, D}),
                      View<double, 2>(V.data() + nfixed_ * NC, {m, NC}),
                      View<double, 4>(F.data() + nfixed_ * cc, {m, NC, NC, D}),
                      View<double, 4>(Wf.data() + nfixed_ * ww, {m, 2 * D, NC, NC}), parts);
  auto sowner = slot_owner_.sized(total);
  auto scell = slot_cell_.sized(total);
  index_t s = nfixed_;
  for (index_t j = 0; j < m; ++j) {
    const index_t c = cand(j), from = nfixed_ + j;
    double fluid = 0.0;
    for (int a = 0; a < NC; ++a) fluid += V(from, a);
    if (fluid <= 0.0) {  // no fluid sub-cell: solid on the staircase
      slot(c) = -1;
      open(c) = 0.0;
      continue;
    }
    if (parts(j) == 0) continue;  // not cut: a whole cell
    if (s != from) {
      std::copy(K.data() + from * kk, K.data() + (from + 1) * kk, K.data() + s * kk);
      std::copy(C.data() + from * cc, C.data() + (from + 1) * cc, C.data() + s * cc);
      std::copy(V.data() + from * NC, V.data() + (from + 1) * NC, V.data() + s * NC);
      std::copy(F.data() + from * cc, F.data() + (from + 1) * cc, F.data() + s * cc);
      std::copy(Wf.data() + from * ww, Wf.data() + (from + 1) * ww, Wf.data() + s * ww);
    }
    slot(c) = s;
    open(c) = fluid / int_power(g_.h, D);
    // the body nearest the cell's corners owns its face
    index_t cx[D], first = 0;
    g_.cell_coords(c, cx);
    for (int k = 0; k < D; ++k) first += cx[k] * g_.ns[k];
    index_t best = first;
    for (int a = 1; a < NC; ++a)
      if (phi(first + g_.corner[a]) < phi(best)) best = first + g_.corner[a];
    sowner(s) = owner(best);
    scell(s) = c;
    ++s;
  }
  nslots_ = s;
  // the obstacle nodes: the fixed ones outside the box, then the box's
  auto inside_box = [&](index_t i) {
    index_t ix[D];
    g_.node_coords(i, ix);
    for (int k = 0; k < D; ++k)
      if (ix[k] < box_lo_[k] || ix[k] > box_hi_[k]) return false;
    return true;
  };
  index_t box_nodes = 1;
  for (int k = 0; k < D; ++k) box_nodes *= box_hi_[k] - box_lo_[k] + 1;
  const index_t most = fixed_.onode.size() + box_nodes;
  auto onode = onode_.sized(most);
  auto onormal = onormal_.template sized<2>({most, D});
  auto slip = ono_slip_.sized(most);
  index_t e = 0;
  for (index_t f = 0; f < fixed_.onode.size(); ++f) {
    const index_t i = fixed_.onode(f);
    if (inside_box(i)) continue;
    onode(e) = i;
    slip(e) = fixed_.ono_slip(f);
    for (int k = 0; k < D; ++k) onormal(e, k) = fixed_.onormal(f, k);
    ++e;
  }
  const double threshold = 1e-9 * int_power(g_.h, D - 1);
  for_box(0, [&](const std::array<index_t, D>& ix) {
    index_t i = 0;
    for (int k = 0; k < D; ++k) i += ix[k] * g_.ns[k];
    double n[D] = {};
    if (nsub_ == 0) {
      if (!staircase_node(ix, i, n)) return;
    } else {
      for (int a = 0; a < NC; ++a) {
        const index_t c = corner_cell(ix, a);
        if (c < 0 || slot(c) < 1) continue;
        const index_t sc = slot(c);
        for (int b = 0; b < NC; ++b)
          for (int k = 0; k < D; ++k) n[k] += F(sc, a, b, k);
      }
      double size = 0.0;
      for (int k = 0; k < D; ++k) size += n[k] * n[k];
      size = std::sqrt(size);
      if (size <= threshold) return;
      for (int k = 0; k < D; ++k) n[k] /= size;
    }
    onode(e) = i;
    for (int k = 0; k < D; ++k) onormal(e, k) = n[k];
    slip(e) = owner(i) >= 0 ? bodies_[owner(i)].no_slip
                            : (fixed_no_slip_.size() > 0 && fixed_no_slip_(i));
    ++e;
  });
  nonode_ = e;
}

template <int D>
void BodyTables<D>::hold(double t) {
  // every box node nearest a body (the obstacle nodes read it; push_out interpolates it)
  if (!placed_) return;
  auto vel = velocity_.template view<2>({g_.nnodes, D});
  auto owner = owner_.view(g_.nnodes);
  for (std::size_t b = 0; b < bodies_.size(); ++b) held_[b] = bodies_[b].pose(t);
  for_box(0, [&](const std::array<index_t, D>& ix) {
    index_t i = 0;
    for (int k = 0; k < D; ++k) i += ix[k] * g_.ns[k];
    if (owner(i) < 0) return;
    double x[D], v[D];
    for (int k = 0; k < D; ++k) x[k] = at(ix[k], k);
    held_[owner(i)].velocity_at(x, v);
    for (int k = 0; k < D; ++k) vel(i, k) = v[k];
  });
}

template <int D>
double BodyTables<D>::max_speed(double t) const {
  double top = 0.0;
  for (const Body<D>& b : bodies_) {
    const Pose<D> q = b.pose(t);
    double reach = 0.0, w = 0.0, v = 0.0;  // the lattice's farthest corner from the centre
    for (int k = 0; k < D; ++k) {
      const double far =
          std::max(std::abs(b.origin[k]), std::abs(b.origin[k] + (b.counts[k] - 1) * b.spacing));
      reach += far * far;
      v += q.velocity[k] * q.velocity[k];
    }
    for (int k = 0; k < 3; ++k) w += q.omega[k] * q.omega[k];
    top = std::max(top, std::sqrt(v) + std::sqrt(w * reach));
  }
  return top;
}

template <int D>
void BodyTables<D>::forces(View<const double> p_node, View<double, 2> force, View<double, 2> torque,
                           View<const bool> owned) {
  for (index_t i = 0; i < force.size(); ++i) force[i] = 0.0;
  for (index_t i = 0; i < torque.size(); ++i) torque[i] = 0.0;
  if (!placed_) return;
  auto F = F_.template view<4>({nslots_, NC, NC, D});
  auto sowner = slot_owner_.view(nslots_);
  auto scell = slot_cell_.view(nslots_);
  for (index_t s = nfixed_; s < nslots_; ++s) {
    if (sowner(s) < 0) continue;
    const index_t c = scell(s);
    if (owned.size() > 0 && !owned(c)) continue;
    const index_t b = sowner(s);
    const Pose<D>& q = poses_[b];
    index_t cx[D], first = 0;
    g_.cell_coords(c, cx);
    for (int k = 0; k < D; ++k) first += cx[k] * g_.ns[k];
    for (int a = 0; a < NC; ++a) {
      double r[3] = {0.0, 0.0, 0.0};
      for (int k = 0; k < D; ++k) r[k] = at(cx[k] + ((a >> k) & 1), k) - q.centre[k];
      for (int bb = 0; bb < NC; ++bb) {
        const double p = p_node(first + g_.corner[bb]);
        double f[3] = {0.0, 0.0, 0.0};
        for (int k = 0; k < D; ++k) f[k] = F(s, a, bb, k) * p;
        for (int k = 0; k < D; ++k) force(b, k) += f[k];
        torque(b, 0) += r[1] * f[2] - r[2] * f[1];
        torque(b, 1) += r[2] * f[0] - r[0] * f[2];
        torque(b, 2) += r[0] * f[1] - r[1] * f[0];
      }
    }
  }
}

template <int D>
void BodyTables<D>::reactions(View<const double, 2> r, View<const bool> ocontact,
                              View<double, 2> force, View<double, 2> torque,
                              View<const bool> owned) {
  for (index_t i = 0; i < force.size(); ++i) force[i] = 0.0;
  for (index_t i = 0; i < torque.size(); ++i) torque[i] = 0.0;
  if (!placed_) return;
  auto owner = owner_.view(g_.nnodes);
  auto onode = onode_.view(nonode_);
  auto onormal = onormal_.template view<2>({nonode_, D});
  auto no_slip = ono_slip_.view(nonode_);
  for (index_t e = 0; e < nonode_; ++e) {
    const index_t i = onode(e), b = owner(i);
    if (b < 0 || !ocontact(i) || (owned.size() > 0 && !owned(i))) continue;
    double f[3] = {0.0, 0.0, 0.0}, arm[3] = {0.0, 0.0, 0.0};
    double rn = 0.0;
    for (int k = 0; k < D; ++k) rn += r(i, k) * onormal(e, k);
    for (int k = 0; k < D; ++k) f[k] = -(no_slip(e) ? r(i, k) : rn * onormal(e, k));
    index_t ix[D];
    g_.node_coords(i, ix);
    for (int k = 0; k < D; ++k) arm[k] = at(ix[k], k) - poses_[b].centre[k];
    for (int k = 0; k < D; ++k) force(b, k) += f[k];
    torque(b, 0) += arm[1] * f[2] - arm[2] * f[1];
    torque(b, 1) += arm[2] * f[0] - arm[0] * f[2];
    torque(b, 2) += arm[0] * f[1] - arm[1] * f[0];
  }
}

template <int D>
ObstacleTables<D> BodyTables<D>::tables() {
  auto& self = *this;
  const index_t nn = g_.nnodes, nc = g_.ncells, n = nslots_;
  ObstacleTables<D> T;
  T.phi = self.phi_.view(nn);
  T.open = self.open_.view(nc);
  T.static_slot = self.slot_.view(nc);
  T.K = self.K_.template view<3>({n, NC, NC});
  T.C = self.C_.template view<4>({n, NC, NC, D});
  T.V = self.V_.template view<2>({n, NC});
  T.F = self.F_.template view<4>({n, NC, NC, D});
  T.Wf = self.Wf_.template view<4>({n, 2 * D, NC, NC});
  T.onode = self.onode_.view(nonode_);
  T.onormal = self.onormal_.template view<2>({nonode_, D});
  T.ono_slip = self.ono_slip_.view(nonode_);
  T.velocity = self.velocity_.template view<2>({nn, D});
  return T;
}

template <int D>
void BodyTables<D>::predict(double dt, const std::array<double, D>& g) {
  for (Body<D>& b : bodies_) {
    if (!b.free) continue;
    for (int k = 0; k < D; ++k)
      b.velocity_star[k] = b.velocity_now[k] + (b.locked[k] ? 0.0 : dt * g[k]);
    b.omega_star = b.omega_now;
    // gravity's torque about a hinge, m (R offset) x g (0 about the centroid)
    const auto R = rotation_of<D>(b.quat);
    std::array<double, 3> arm{}, weight{};
    for (int k = 0; k < D; ++k) {
      weight[k] = b.mass * g[k];
      for (int j = 0; j < D; ++j) arm[k] += R[k][j] * b.offset[j];
    }
    const auto lever = cross(arm, weight);
    if constexpr (D == 2) {
      if (!b.locked[2]) b.omega_star[2] += dt * lever[2] / b.inertia[2][2];
    } else {  // omega' = I^-1 (m r x g - omega x I omega), explicitly
      const auto Iw = world_inertia(R, b.inertia);
      std::array<double, 3> Iomega{};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Iomega[i] += Iw[i][j] * b.omega_now[j];
      const auto torque = cross(b.omega_now, Iomega);
      double A[9], rhs[3] = {lever[0] - torque[0], lever[1] - torque[1], lever[2] - torque[2]};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) A[i * 3 + j] = Iw[i][j];
      if (solve_dense(3, A, rhs))
        for (int k = 0; k < 3; ++k)
          if (!b.locked[D + k]) b.omega_star[k] += dt * rhs[k];
    }
  }
  reset_velocity();
}

template <int D>
void BodyTables<D>::reset_velocity() {
  for (Body<D>& b : bodies_)
    if (b.free) {
      b.velocity_now = b.velocity_star;
      b.omega_now = b.omega_star;
    }
}

template <int D>
void BodyTables<D>::coupling(View<const index_t> cell_slot, View<const index_t> node_row,
                             View<const bool> ocontact, View<double, 2> J, View<double, 2> K) {
  for (index_t i = 0; i < J.size(); ++i) J[i] = 0.0;
  for (index_t i = 0; i < K.size(); ++i) K[i] = 0.0;
  auto F = F_.template view<4>({nslots_, NC, NC, D});
  auto sowner = slot_owner_.view(nslots_);
  auto scell = slot_cell_.view(nslots_);
  auto owner = owner_.view(g_.nnodes);
  constexpr int NR = D == 2 ? 1 : 3;
  // G_d(x) . f for the body's degree of freedom kind at arm r (translation k: f_k; rotation
  // about axis m: (r x f)_m)
  auto along = [](index_t kind, const std::array<double, 3>& r, const std::array<double, 3>& f) {
    if (kind < D) return f[kind];
    const auto rf = cross(r, f);
    return D == 2 ? rf[2] : rf[kind - D];
  };
  for (index_t s = nfixed_; s < nslots_; ++s) {
    const index_t b = sowner(s);
    if (b < 0 || !bodies_[b].free) continue;
    const index_t c = scell(s);
    if (cell_slot(c) < 0) continue;
    const Pose<D>& q = poses_[b];
    index_t cx[D], first = 0;
    g_.cell_coords(c, cx);
    for (int k = 0; k < D; ++k) first += cx[k] * g_.ns[k];
    std::array<std::array<double, 3>, NC> arm{};
    for (int a = 0; a < NC; ++a)
      for (int k = 0; k < D; ++k) arm[a][k] = at(cx[k] + ((a >> k) & 1), k) - q.centre[k];
    for (int a = 0; a < NC; ++a) {
      const index_t ia = first + g_.corner[a], ra = node_row(ia);
      for (int bb = 0; bb < NC; ++bb) {
        const index_t jb = first + g_.corner[bb], rb = node_row(jb);
        std::array<double, 3> f{};
        for (int k = 0; k < D; ++k) f[k] = F(s, a, bb, k);
        for (index_t kind = 0; kind < D + NR; ++kind) {
          const index_t d = dof_of_[b][kind];
          if (d < 0) continue;
          if (ra >= 0 && ocontact(jb) && owner(jb) == b) J(d, ra) += along(kind, arm[bb], f);
          if (rb >= 0) K(d, rb) += along(kind, arm[a], f);
        }
      }
    }
  }
}

template <int D>
void BodyTables<D>::mass_matrix(View<double, 2> M) const {
  const index_t n = free_dofs();
  for (index_t i = 0; i < M.size(); ++i) M[i] = 0.0;
  for (index_t i = 0; i < n; ++i)
    for (index_t j = 0; j < n; ++j) {
      const auto [bi, ki] = dofs_[i];
      const auto [bj, kj] = dofs_[j];
      if (bi != bj) continue;
      const Body<D>& b = bodies_[bi];
      if (ki < D || kj < D) {
        if (ki == kj) M(i, j) = b.mass;
        continue;
      }
      if constexpr (D == 2) {
        M(i, j) = b.inertia[2][2];
      } else {
        M(i, j) = world_inertia(rotation_of<3>(b.quat), b.inertia)[ki - D][kj - D];
      }
    }
}

template <int D>
void BodyTables<D>::apply_impulse(View<const double> impulse) {
  const index_t n = free_dofs();
  if (n == 0) return;
  auto M = small_.template view<2>({n, n});
  mass_matrix(M);
  auto dq = rhs_small_.view(n);
  for (index_t i = 0; i < n; ++i) dq(i) = impulse(i);
  if (!solve_dense(n, M.data(), dq.data()))
    throw std::logic_error("BodyTables: a free body's mass matrix is singular");
  reset_velocity();
  for (index_t i = 0; i < n; ++i) {
    const auto [b, kind] = dofs_[i];
    Body<D>& body = bodies_[b];
    if (kind < D)
      body.velocity_now[kind] += dq(i);
    else
      body.omega_now[D == 2 ? 2 : kind - D] += dq(i);
  }
}

template <int D>
void BodyTables<D>::integrate(double dt, double t, Exchange<D>* exchange) {
  // the contacts first, where the bodies are (semi-implicit Euler: the move takes the
  // velocities the contacts left, so that a body held by static friction on an incline
  // stays where it is, and one resting on the floor does not sink and come back each step)
  contact(t - dt, dt, exchange);
  for (Body<D>& b : bodies_) {
    if (!b.free) continue;
    for (int k = 0; k < D; ++k) b.centre_now[k] += dt * b.velocity_now[k];
    // q += dt/2 (0, omega) q, normalized
    const auto& w = b.omega_now;
    const std::array<double, 3> v = {b.quat[1], b.quat[2], b.quat[3]};
    const auto wv = cross(w, v);
    std::array<double, 4> dq = {-(w[0] * v[0] + w[1] * v[1] + w[2] * v[2]),
                                b.quat[0] * w[0] + wv[0], b.quat[0] * w[1] + wv[1],
                                b.quat[0] * w[2] + wv[2]};
    double norm = 0.0;
    for (int k = 0; k < 4; ++k) {
      b.quat[k] += 0.5 * dt * dq[k];
      norm += b.quat[k] * b.quat[k];
    }
    norm = std::sqrt(norm);
    for (int k = 0; k < 4; ++k) b.quat[k] /= norm;
    b.velocity_star = b.velocity_now;
    b.omega_star = b.omega_now;
  }
}

template <int D>
std::array<std::array<double, 3>, 3> BodyTables<D>::inverse_inertia(const Body<D>& b) const {
  std::array<std::array<double, 3>, 3> Iinv{};
  if constexpr (D == 2) {
    if (!b.locked[2]) Iinv[2][2] = 1.0 / b.inertia[2][2];
  } else {
    const auto Iw = world_inertia(rotation_of<3>(b.quat), b.inertia);
    for (int c = 0; c < 3; ++c) {
      double A[9], t[3] = {0.0, 0.0, 0.0};
      t[c] = 1.0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) A[i * 3 + j] = Iw[i][j];
      if (solve_dense(3, A, t))
        for (int i = 0; i < 3; ++i) Iinv[i][c] = b.locked[3 + i] || b.locked[3 + c] ? 0.0 : t[i];
    }
  }
  return Iinv;
}

template <int D>
index_t BodyTables<D>::contact(double t, double dt, Exchange<D>* exchange) {
  index_t count = 0;
  const double touch = 1e-3 * g_.h;  // a point this close counts as touching (resting)
  // a point this close is a contact ahead (speculative): the move may not close its gap
  // faster than gap / dt (a box rocking on one corner meets the floor with the other)
  const double reach = 0.5 * g_.h;
  const index_t nb = static_cast<index_t>(bodies_.size());
  for (index_t a = 0; a < nb; ++a) {
    Body<D>& b = bodies_[a];
    if (!b.free || b.surface.size() == 0) continue;
    // the other bodies where they are now (a free one after the contacts before this one's)
    for (index_t o = 0; o < nb; ++o) {
      contact_poses_[o] = bodies_[o].pose(t);
      if (bodies_[o].free) inverse_inertia_[o] = inverse_inertia(bodies_[o]);
    }
    const auto R = rotation_of<D>(b.quat);
    const index_t m = b.surface.extent(0);
    // the contacts: each surface point beyond (or on) a wall or inside (or on) a fixed
    // obstacle or another body, with the normal out of it, into contacts_ as (point, normal,
    // impulse, the other body or -1); the deepest one's normal and depth
    double deepest = 0.0;
    std::array<double, 3> push{};
    index_t nc = 0;
    auto contacts = contacts_.template view<2>({contacts_.capacity() / CONTACT, CONTACT});
    auto add = [&](const std::array<double, D>& x, const double* n, double depth, index_t other) {
      if (nc >= contacts.extent(0)) return;
      for (int k = 0; k < 3; ++k) {
        contacts(nc, k) = k < D ? x[k] : 0.0;
        contacts(nc, 3 + k) = k < D ? n[k] : 0.0;
      }
      contacts(nc, 6) = 0.0;  // the impulse it has taken so far
      contacts(nc, 7) = static_cast<double>(other);
      for (int k = 8; k < 11; ++k) contacts(nc, k) = 0.0;  // the friction's likewise
      contacts(nc, 11) = depth > -touch ? 0.0 : -depth;    // the gap ahead (m)
      ++nc;
      if (depth > deepest) {
        deepest = depth;
        push = {};
        for (int k = 0; k < D; ++k) push[k] = n[k];
      }
    };
    // a distance's gradient at x by central differences over half the body's lattice
    // spacing, into n (unit); returns its length (0 where the lattice does not reach)
    auto gradient = [&](const Body<D>& body, const Pose<D>& q, const std::array<double, D>& x,
                        double* n) {
      double gn = 0.0;
      for (int k = 0; k < D; ++k) {
        std::array<double, D> xp = x, xm = x;
        xp[k] += 0.5 * body.spacing;
        xm[k] -= 0.5 * body.spacing;
        const double up = body.distance(q, xp.data()), down = body.distance(q, xm.data());
        if (!(up < FAR && down < FAR)) return 0.0;
        n[k] = (up - down) / body.spacing;
        gn += n[k] * n[k];
      }
      gn = std::sqrt(gn);
      for (int k = 0; k < D; ++k) n[k] = gn > 0.0 ? n[k] / gn : 0.0;
      return gn;
    };
    // the contact's normal (out of what is touched): this body's own inward normal where
    // its surface is flat at the point (its distance's gradient of length 1 to FLAT; at an
    // edge or corner the interpolated distance's gradient shortens and turns), else that of
    // what it touches: a face resting on another body's edge is pushed along its own normal,
    // not sideways by the edge's rounded distance (a box resting across an edge slid off,
    // frictionless), and a corner resting on a face along the face's
    const Pose<D> self = b.pose(t);
    auto flatter = [&](const std::array<double, D>& x, double* n) {
      double own[D];
      if (gradient(b, self, x, own) >= FLAT)
        for (int k = 0; k < D; ++k) n[k] = -own[k];
    };
    auto point = [&](index_t e) {
      std::array<double, D> x;
      for (int k = 0; k < D; ++k) {
        x[k] = b.centre_now[k];
        for (int j = 0; j < D; ++j) x[k] += R[k][j] * b.surface(e, j);
      }
      return x;
    };
    // the fixed obstacles' phi and gradient at each point, read by the rank that owns the
    // point's cell (its grid holds the cell's nodes) and summed over the ranks, so that
    // every rank takes the same contacts (on one process: this grid's cells, all owned)
    // (summed on every rank alike, whether its grid holds a fixed obstacle or not)
    auto fixed_at = fixed_at_.template view<2>({m, D + 2});
    for (index_t i = 0; i < fixed_at.size(); ++i) fixed_at[i] = 0.0;
    if (fixed_.phi.size() > 0) {
      const View<const bool> owned =
          exchange != nullptr ? exchange->owned_cells() : View<const bool>{};
      for (index_t e = 0; e < m; ++e) {
        const auto x = point(e);
        bool inside = true;  // on this grid (a rank's: its origin_ cells from the domain's)
        std::array<double, D> local;
        index_t c = 0;
        for (int k = 0; k < D; ++k) {
          local[k] = x[k] - static_cast<double>(origin_[k]) * g_.h;
          inside = inside && local[k] >= 0.0 && local[k] <= g_.cells[k] * g_.h;
          // the point's cell from the domain's frame, alike on every rank
          const index_t ck =
              std::min(static_cast<index_t>(std::floor(x[k] / g_.h)), domain_[k] - 1) - origin_[k];
          inside = inside && ck >= 0 && ck < g_.cells[k];
          c += (inside ? ck : 0) * g_.cs[k];
        }
        if (!inside || (owned.size() > 0 && !owned(c))) continue;
        double grad[D];
        fixed_at(e, 0) = interpolate_phi<D>(g_, fixed_.phi,
                                            View<const double, 2>(local.data(), {1, D}), 0, grad);
        for (int k = 0; k < D; ++k) fixed_at(e, 1 + k) = grad[k];
        fixed_at(e, D + 1) = 1.0;
      }
    }
    if (exchange != nullptr) exchange->sum_values(View<double>(fixed_at.data(), {m * (D + 2)}));
    for (index_t e = 0; e < m; ++e) {
      const std::array<double, D> x = point(e);
      for (int k = 0; k < D; ++k) {
        if (g_.periodic[k]) continue;
        double n[D] = {};
        // the domain's walls (on a rank, not its grid's edges: x is in the domain's frame)
        const double below = -x[k], above = x[k] - domain_[k] * g_.h;
        if (below > -reach) {
          n[k] = 1.0;
          add(x, n, below, -1);
        }
        if (above > -reach) {
          n[k] = -1.0;
          add(x, n, above, -1);
        }
      }
      if (fixed_at(e, D + 1) > 0.0) {  // a fixed obstacle: phi, its gradient
        const double px = fixed_at(e, 0);
        double grad[D];
        for (int k = 0; k < D; ++k) grad[k] = fixed_at(e, 1 + k);
        double gn = 0.0;
        for (int k = 0; k < D; ++k) gn += grad[k] * grad[k];
        gn = std::sqrt(gn);
        if (px < reach && gn > 0.01) {
          double n[D];
          for (int k = 0; k < D; ++k) n[k] = grad[k] / gn;
          flatter(x, n);
          add(x, n, -px, -1);
        }
      }
      for (index_t o = 0; o < nb; ++o) {  // another body: its distance, its gradient
        if (o == a) continue;
        const Body<D>& other = bodies_[o];
        const double po = other.distance(contact_poses_[o], x.data());
        if (!(po < reach)) continue;
        double n[D];
        const double gn = gradient(other, contact_poses_[o], x, n);
        if (!(gn > 0.01)) continue;
        flatter(x, n);
        add(x, n, -po, o);
      }
    }
    if (nc == 0) continue;
    count += nc;
    // back out along the deepest contact's normal (the held translations stay)
    for (int k = 0; k < D; ++k)
      if (!b.locked[k]) b.centre_now[k] += deepest * push[k];
    const auto Iinv = inverse_inertia(b);
    // a body's share of a contact's inverse mass along n, and the turn an impulse along n
    // gives it
    auto share = [&](const Body<D>& body, const std::array<std::array<double, 3>, 3>& I,
                     const std::array<double, 3>& r, const std::array<double, 3>& n,
                     std::array<double, 3>& turn) {
      double inv = 0.0;
      for (int k = 0; k < D; ++k)
        if (!body.locked[k]) inv += n[k] * n[k] / body.mass;
      const auto rn = cross(r, n);
      turn = {};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) turn[i] += I[i][j] * rn[j];
      for (int k = 0; k < 3; ++k) inv += rn[k] * turn[k];
      return inv;
    };
    // an impulse P (3) at r from the centre into a body's velocities (sign -1: the reaction)
    auto impulse = [&](Body<D>& body, const std::array<std::array<double, 3>, 3>& I,
                       const std::array<double, 3>& r, const std::array<double, 3>& P,
                       double sign) {
      for (int k = 0; k < D; ++k)
        if (!body.locked[k]) body.velocity_now[k] += sign * P[k] / body.mass;
      const auto rp = cross(r, P);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) body.omega_now[i] += sign * I[i][j] * rp[j];
    };
    // projected Gauss-Seidel on the contacts' impulses, contact by contact in sweeps until
    // they agree: the normal impulse (>= 0, pushing only) that zeroes the contact's normal
    // velocity (relative to the other body's there) added to what it has taken, clamped at 0
    // (a contact may give back what an earlier one made it take): an inelastic landing (two
    // corners of a box resting flat). Then Coulomb's friction: the tangential impulse that
    // stops the sliding at the point, added to what it has taken and held within mu times
    // the normal impulse (mu: the body's friction; between two free bodies the geometric mean
    // of theirs). A free other body takes the opposite impulses; a body on a path is not
    // moved by them.
    for (int sweep = 0; sweep < 500; ++sweep) {
      double change = 0.0;
      for (index_t c = 0; c < nc; ++c) {
        std::array<double, 3> r{}, n{}, x{};
        for (int k = 0; k < 3; ++k) {
          x[k] = contacts(c, k);
          r[k] = x[k] - (k < D ? b.centre_now[k] : 0.0);
          n[k] = contacts(c, 3 + k);
        }
        const auto o = static_cast<index_t>(contacts(c, 7));
        Body<D>* other = o >= 0 && bodies_[o].free ? &bodies_[o] : nullptr;
        std::array<double, 3> r_o{};
        if (other != nullptr)
          for (int k = 0; k < D; ++k) r_o[k] = x[k] - other->centre_now[k];
        // the velocity at the point relative to what it touches
        auto relative = [&]() {
          std::array<double, 3> u{};
          const auto w = cross(b.omega_now, r);
          for (int k = 0; k < D; ++k) u[k] = b.velocity_now[k] + w[k];
          if (other != nullptr) {
            const auto wo = cross(other->omega_now, r_o);
            for (int k = 0; k < D; ++k) u[k] -= other->velocity_now[k] + wo[k];
          } else if (o >= 0) {
            double uo[D];
            contact_poses_[o].velocity_at(x.data(), uo);
            for (int k = 0; k < D; ++k) u[k] -= uo[k];
          }
          return u;
        };
        // the contact's inverse mass along a direction d
        auto inverse_mass = [&](const std::array<double, 3>& d) {
          std::array<double, 3> turn{};
          double inv = share(b, Iinv, r, d, turn);
          if (other != nullptr) inv += share(*other, inverse_inertia_[o], r_o, d, turn);
          return inv;
        };
        auto apply = [&](const std::array<double, 3>& P) {
          impulse(b, Iinv, r, P, 1.0);
          if (other != nullptr) impulse(*other, inverse_inertia_[o], r_o, P, -1.0);
        };
        {  // the normal impulse (as written before friction, to the last bit)
          const auto w = cross(b.omega_now, r);
          double vn = 0.0;
          for (int k = 0; k < D; ++k) vn += (b.velocity_now[k] + w[k]) * n[k];
          std::array<double, 3> turn{}, turn_o{};
          double inv = share(b, Iinv, r, n, turn);
          if (other != nullptr) {
            const auto wo = cross(other->omega_now, r_o);
            for (int k = 0; k < D; ++k) vn -= (other->velocity_now[k] + wo[k]) * n[k];
            inv += share(*other, inverse_inertia_[o], r_o, n, turn_o);
          } else if (o >= 0) {
            double u[D];
            contact_poses_[o].velocity_at(x.data(), u);
            for (int k = 0; k < D; ++k) vn -= u[k] * n[k];
          }
          const double taken = contacts(c, 6);
          // inv 0: every degree of freedom along it is held
          // the normal velocity may close the gap ahead over the step, not more
          const double ahead = contacts(c, 11) / dt;
          const double now = inv > 0.0 ? std::max(0.0, taken - (vn + ahead) / inv) : taken;
          const double j = now - taken;
          if (j != 0.0) {
            contacts(c, 6) = now;
            change = std::max(change, std::abs(j) * inv);  // the velocity it changed (m/s)
            for (int k = 0; k < D; ++k)
              if (!b.locked[k]) b.velocity_now[k] += j * n[k] / b.mass;
            for (int k = 0; k < 3; ++k) b.omega_now[k] += j * turn[k];
            if (other != nullptr) {
              for (int k = 0; k < D; ++k)
                if (!other->locked[k]) other->velocity_now[k] -= j * n[k] / other->mass;
              for (int k = 0; k < 3; ++k) other->omega_now[k] -= j * turn_o[k];
            }
          }
        }
        const double mu = other != nullptr ? std::sqrt(b.friction * other->friction) : b.friction;
        if (!(mu > 0.0)) continue;
        const auto u = relative();
        double un = 0.0;
        for (int k = 0; k < D; ++k) un += u[k] * n[k];
        std::array<double, 3> slide{}, before{}, after{};
        double speed = 0.0;
        for (int k = 0; k < 3; ++k) {
          slide[k] = u[k] - un * n[k];
          speed += slide[k] * slide[k];
          before[k] = after[k] = contacts(c, 8 + k);
        }
        speed = std::sqrt(speed);
        if (speed > 0.0) {
          std::array<double, 3> t{};
          for (int k = 0; k < 3; ++k) t[k] = slide[k] / speed;
          const double inv_t = inverse_mass(t);
          if (inv_t > 0.0)
            for (int k = 0; k < 3; ++k) after[k] -= speed / inv_t * t[k];
        }
        const double limit = mu * contacts(c, 6);
        double size = 0.0;
        for (int k = 0; k < 3; ++k) size += after[k] * after[k];
        size = std::sqrt(size);
        if (size > limit)
          for (int k = 0; k < 3; ++k) after[k] *= limit / size;
        std::array<double, 3> dP{};
        double step = 0.0;
        for (int k = 0; k < 3; ++k) {
          dP[k] = after[k] - before[k];
          step += dP[k] * dP[k];
          contacts(c, 8 + k) = after[k];
        }
        if (step == 0.0) continue;
        change = std::max(change, std::sqrt(step) / b.mass);
        apply(dP);
      }
      if (change < 1e-9) break;
    }
    for (Body<D>& body : bodies_) {
      body.velocity_star = body.velocity_now;
      body.omega_star = body.omega_now;
    }
  }
  return count;
}

template <int D>
void BodyTables<D>::state(double t, View<double, 2> out) const {
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    const Body<D>& body = bodies_[b];
    const Pose<D> q = body.pose(t);
    for (int k = 0; k < 13; ++k) out(b, k) = 0.0;
    for (int k = 0; k < D; ++k) {
      out(b, k) = q.centre[k];
      out(b, 3 + k) = q.velocity[k];
    }
    for (int k = 0; k < 3; ++k) out(b, 6 + k) = q.omega[k];
    if (body.free) {
      for (int k = 0; k < 4; ++k) out(b, 9 + k) = body.quat[k];
    } else {
      out(b, 9) = std::cos(0.5 * q.angle);
      for (int k = 0; k < 3; ++k) out(b, 10 + k) = body.axis[k] * std::sin(0.5 * q.angle);
    }
  }
}

template <int D>
void BodyTables<D>::set_state(View<const double, 2> in) {
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    Body<D>& body = bodies_[b];
    if (!body.free) continue;
    for (int k = 0; k < D; ++k) {
      body.centre_now[k] = in(b, k);
      body.velocity_now[k] = body.velocity_star[k] = in(b, 3 + k);
    }
    for (int k = 0; k < 3; ++k) body.omega_now[k] = body.omega_star[k] = in(b, 6 + k);
    for (int k = 0; k < 4; ++k) body.quat[k] = in(b, 9 + k);
  }
}

template struct Pose<2>;
template struct Pose<3>;
template struct Body<2>;
template struct Body<3>;
template class BodyTables<2>;
template class BodyTables<3>;

}  // namespace mpmflow
