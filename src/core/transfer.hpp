// Particle-grid transfers with multilinear shape functions, for 2D and 3D
// (docs/method.md, steps 2 and 7).
//
// Particle-to-grid: nodal mass, momentum and material volume, the velocity and the
// predictor with gravity, and (for the volume correction) the particles' volume on the
// cell centres; grid-to-particle: the FLIP/PIC velocity, the position moved with the new
// grid velocity plus the volume correction's displacement, the pressure, and the wall
// put-back. The element functions (scatter_cell_volume, face_samples, face_displacement,
// put_inside) are inline here: other kernels call them per particle.
#pragma once

#include <array>
#include <cmath>

#include "grid.hpp"
#include "periodic.hpp"
#include "strips.hpp"
#include "view.hpp"

namespace mpmflow {

constexpr double FLIP_TIME = 1e-3;  // s: solver.flip is the FLIP fraction per this much time

// The FLIP fraction of one step of dt (s): flip_rate^(dt / FLIP_TIME), the same PIC damping
// per second of flow whatever the step (both schemes, fixed and adaptive steps).
inline double flip_per_step(double flip_rate, double dt) {
  return std::pow(flip_rate, dt / FLIP_TIME);
}

// The multilinear hat of the cell-centred grid at point x (D coordinates, m): for each of
// its 2^D corners, body(i, w) with i the corner cell's coordinates and w = volume times its
// weight. A wall mirrors the points next to it: a ghost cell's weight goes to its mirror,
// the cell against the wall, so a uniform material reads full up to the walls; a periodic
// axis wraps round. Points beyond the grid (and NaN) count at its edge.
template <int D, bool P = true, class F>
MPMFLOW_HD inline void cell_centre_hat(const Grid<D>& g, const double* x, double volume, F&& body) {
  std::array<double, D> frac;
  std::array<index_t, D> first;
  for (int k = 0; k < D; ++k) {
    double s = x[k] * g.inv_h;
    if (!(s >= 0.0))
      s = 0.0;
    else if (s > g.cells[k])
      s = static_cast<double>(g.cells[k]);
    s -= 0.5;
    const index_t i0 = static_cast<index_t>(s + 1.0) - 1;  // floor: s >= -1/2
    frac[k] = s - i0;
    first[k] = i0;
  }
  for (int a = 0; a < (1 << D); ++a) {
    std::array<index_t, D> i;
    double w = volume;
    for (int k = 0; k < D; ++k) {
      const int up = (a >> k) & 1;
      i[k] = first[k] + up;
      w *= up ? frac[k] : 1.0 - frac[k];
      if (P && g.periodic[k])
        i[k] = g.wrap_cell(k, i[k]);
      else if (i[k] < 0)
        i[k] = 0;
      else if (i[k] > g.cells[k] - 1)
        i[k] = g.cells[k] - 1;
    }
    body(i, w);
  }
}

// Add ``volume`` (m^3) at particle p to the cell centres (cell_centre_hat).
template <int D>
MPMFLOW_HD inline void scatter_cell_volume(const Grid<D>& g, View<const double, 2> x, index_t p,
                                           double volume, View<double> cell_vol) {
  cell_centre_hat<D>(g, &x(p, 0), volume, [&](const std::array<index_t, D>& i, double w) {
    index_t c = 0;
    for (int k = 0; k < D; ++k) c += i[k] * g.cs[k];
    cell_vol[c] += w;
  });
}

// Where particle p samples the face values of the volume correction: along an axis j whose
// faces it interpolates across (normal to them), between faces nlo[j] and nlo[j] + 1 with
// the weight normal[j] of the upper one; along an axis whose faces lie at cell centres,
// between tlo[j] and thi[j] (clamped to the outermost; wrapped round a periodic axis) with
// weight tangent[j]. Points
// beyond the grid count at its edge.
template <int D>
MPMFLOW_HD inline void face_samples(const Grid<D>& g, View<const double, 2> x, index_t p,
                                    std::array<double, D>& normal, std::array<index_t, D>& nlo,
                                    std::array<double, D>& tangent, std::array<index_t, D>& tlo,
                                    std::array<index_t, D>& thi) {
  for (int j = 0; j < D; ++j) {
    double s = x(p, j) * g.inv_h;
    if (!(s >= 0.0))
      s = 0.0;
    else if (s > g.cells[j])
      s = static_cast<double>(g.cells[j]);
    index_t i0 = static_cast<index_t>(s);
    if (i0 > g.cells[j] - 1) i0 = g.cells[j] - 1;
    nlo[j] = i0;
    normal[j] = s - i0;
    s -= 0.5;
    i0 = static_cast<index_t>(s + 1.0) - 1;  // floor: s >= -1/2
    tangent[j] = s - i0;
    if (g.periodic[j]) {
      tlo[j] = g.wrap_cell(j, i0);
      thi[j] = g.wrap_cell(j, i0 + 1);
    } else {
      tlo[j] = i0 > 0 ? i0 : 0;
      thi[j] = i0 + 1 < g.cells[j] - 1 ? i0 + 1 : g.cells[j] - 1;
    }
  }
}

// Component k of the volume correction's displacement at a particle (m), interpolated
// multilinearly from f, the values on the cell faces normal to axis k (face (i_0, ...) at
// i_k h along axis k, i_k = 0 to cells[k], and at (i_j + 1/2) h along the others, flat
// index with axis 0 fastest), at the samples face_samples found.
template <int D>
MPMFLOW_HD inline double face_displacement(const Grid<D>& g, int k, View<const double> f,
                                           const std::array<double, D>& normal,
                                           const std::array<index_t, D>& nlo,
                                           const std::array<double, D>& tangent,
                                           const std::array<index_t, D>& tlo,
                                           const std::array<index_t, D>& thi) {
  double acc = 0.0;
  for (int a = 0; a < (1 << D); ++a) {
    double w = 1.0;
    index_t idx = 0;
    index_t stride = 1;
    for (int j = 0; j < D; ++j) {
      const int up = (a >> j) & 1;
      if (j == k) {
        w *= up ? normal[j] : 1.0 - normal[j];
        idx += (nlo[j] + up) * stride;
        stride *= g.cells[j] + 1;
      } else {
        w *= up ? tangent[j] : 1.0 - tangent[j];
        idx += (up ? thi[j] : tlo[j]) * stride;
        stride *= g.cells[j];
      }
    }
    acc += w * f[idx];
  }
  return acc;
}

// Move particle p that left a periodic axis's [0, cells h) by one period (m) back into it.
template <int D>
MPMFLOW_HD inline void wrap_periodic(const Grid<D>& g, View<double, 2> x, index_t p) {
  for (int k = 0; k < D; ++k) {
    if (!g.periodic[k]) continue;
    const double length = g.cells[k] * g.h;
    double& xk = x(p, k);
    if (xk < 0.0)
      xk += length;
    else if (xk >= length)
      xk -= length;
  }
}

// Put particle p back inside the box [lower, upper] (m) if it left it; true if it was moved.
// A particle beyond a wall is mirrored back across it (so it keeps its distance from the
// wall) and at least ``margin`` (m) inside; its velocity component into the wall is removed.
// lower is the domain's lower corner: 0 for a grid on the whole domain, the domain's corner
// in the grid's coordinates for a grid on a part of it (with lower 0 the same numbers as
// before it was given: 0 + margin and 0 - x are exact).
template <int D>
MPMFLOW_HD inline bool put_inside(View<double, 2> x, View<double, 2> v, index_t p,
                                  View<const double> lower, View<const double> upper,
                                  double margin) {
  bool out = false;
  for (int k = 0; k < D; ++k) {
    const double lo = lower(k) + margin;
    const double hi = upper(k) - margin;
    double& xk = x(p, k);
    if (xk < lower(k)) {
      const double mirror = 2.0 * lower(k) - xk;
      const double m = lo > mirror ? lo : mirror;  // min(max(mirror, lo), hi) as Python takes them
      xk = hi < m ? hi : m;
      if (v(p, k) < 0.0) v(p, k) = 0.0;
      out = true;
    } else if (xk > upper(k)) {
      const double mirror = 2.0 * upper(k) - xk;
      const double m = hi < mirror ? hi : mirror;
      xk = lo > m ? lo : m;
      if (v(p, k) > 0.0) v(p, k) = 0.0;
      out = true;
    }
  }
  return out;
}

// Outlets, the open sides of the domain (domain.walls = "outlet"): side has one flag per side
// in the order x_min, x_max, y_min, ... (empty: none). A particle that crosses an outlet side
// leaves the domain: it is retired in place (mass, volume, velocity, pressure and affine
// matrix set to 0, so that it carries nothing to the grid; its position put back inside the
// box so that binning stays in range) and skipped by later steps; Python removes the retired
// particles (mass 0) between chunks, as it owns the particle arrays' sizes.
struct Outlets {
  View<const bool> side;
  View<double> mass, volume;
  // the particle arrays hold inlets' dormant particles (mass 0, inlets.hpp), skipped too
  bool dormant = false;
  MPMFLOW_HD bool any() const { return side.size() > 0; }
  MPMFLOW_HD bool skips(index_t p) const { return (any() || dormant) && mass(p) == 0.0; }
};

// True when particle p lies beyond an outlet side of the box [lower, upper].
template <int D>
MPMFLOW_HD inline bool beyond_outlet(View<const double, 2> x, index_t p, View<const double> lower,
                                     View<const double> upper, View<const bool> side) {
  for (int k = 0; k < D; ++k) {
    if (x(p, k) < lower(k) && side(2 * k)) return true;
    if (x(p, k) > upper(k) && side(2 * k + 1)) return true;
  }
  return false;
}

// Particle-to-grid's element function: particle p's share at corner a of its cell, whose
// weight there is w (weights_at) and whose first node has coordinates nx (APIC only), added
// to the corner's sums of mass am (kg), volume av (m^3) and momentum amom (D components,
// kg m/s). The host's slab scatter and the device's node gather (src/core/cuda/) both add
// through it, so a node's sums take the same terms.
template <int D>
MPMFLOW_HD inline void p2g_corner(const Grid<D>& g, index_t p, int a, double w, const index_t* nx,
                                  View<const double, 2> x, View<const double, 2> v,
                                  View<const double> mass, View<const double> volume,
                                  View<const double, 3> affine, double& am, double& av,
                                  double* amom) {
  const double wm = w * mass(p);
  am += wm;
  av += w * volume(p);
  if (affine.size() > 0) {
    // the particle's affine field at the corner node: v_p + C_p (x_i - x_p)
    double dx[D];
    for (int j = 0; j < D; ++j) dx[j] = static_cast<double>(nx[j] + ((a >> j) & 1)) * g.h - x(p, j);
    for (int k = 0; k < D; ++k) {
      double vi = v(p, k);
      for (int j = 0; j < D; ++j) vi += affine(p, k, j) * dx[j];
      amom[k] += wm * vi;
    }
  } else {
    for (int k = 0; k < D; ++k) amom[k] += wm * v(p, k);
  }
}

// Grid-to-particle's element function (eqs. 19-21, grid_to_particles below says what it
// does): the arrays and settings of one call, applied to one particle by operator(), which
// returns true when the particle was put back inside the box. Plain views and numbers, so
// the host's loop and the device's kernel (src/core/cuda/) take it by value.
template <int D>
struct GridToParticle {
  Grid<D> g;
  View<double, 2> x, v;
  View<double> pressure;
  View<const double, 2> v_old, v_new;
  View<const double> p_node;
  double dt = 0.0, flip = 1.0, margin = 0.0;
  View<const double> lower, upper;
  std::array<View<const double>, D> faces;
  View<double, 3> affine;
  Outlets outlets;

  // The particle's new velocity from its old one vp, the grid's change at it dv and the
  // grid's velocity at it pic: APIC's PIC velocity, or the FLIP/PIC blend.
  MPMFLOW_HD double blend(bool apic, double vp, double dv, double pic) const {
    return apic ? pic : flip * (vp + dv) + (1.0 - flip) * pic;
  }

  // The velocity operator() gives particle p (m/s, into out), without moving it (a solid's
  // stress update maps it back to the grid: solid.hpp).
  MPMFLOW_HD void new_velocity(index_t p, double* out) const {
    constexpr int NC = Grid<D>::NC;
    double w[NC];
    const index_t base = g.weights_at(&x(p, 0), w);
    double pic[D] = {}, dv[D] = {};
    for (int a = 0; a < NC; ++a) {
      const index_t i = base + g.corner[a];
      for (int k = 0; k < D; ++k) {
        pic[k] = pic[k] + w[a] * v_new(i, k);
        dv[k] = dv[k] + w[a] * (v_new(i, k) - v_old(i, k));
      }
    }
    for (int k = 0; k < D; ++k) out[k] = blend(affine.size() > 0, v(p, k), dv[k], pic[k]);
  }

  MPMFLOW_HD bool operator()(index_t p) const {
    constexpr int NC = Grid<D>::NC;
    if (outlets.skips(p)) return false;  // left through an outlet, or an inlet's dormant one
    const bool correct = faces[0].size() > 0;
    const bool apic = affine.size() > 0;
    double w[NC];
    const index_t base = g.weights_at(&x(p, 0), w);
    std::array<double, D> pic{}, dv{}, disp{};
    double pp = 0.0;
    if (apic) {
      // PIC velocity and C_p = sum_i v_i (grad N_i)^T of the corrected grid velocity
      double frac[D];
      g.locate(&x(p, 0), frac);
      double C[D][D] = {};
      for (int a = 0; a < NC; ++a) {
        const index_t i = base + g.corner[a];
        double grad[D];
        for (int j = 0; j < D; ++j) grad[j] = g.corner_gradient(a, j, frac);
        for (int k = 0; k < D; ++k) {
          const double vi = v_new(i, k);
          pic[k] += w[a] * vi;
          for (int j = 0; j < D; ++j) C[k][j] += vi * grad[j];
        }
        pp += w[a] * p_node(i);
      }
      for (int k = 0; k < D; ++k)
        for (int j = 0; j < D; ++j) affine(p, k, j) = C[k][j];
    } else {
      for (int a = 0; a < NC; ++a) {
        const index_t i = base + g.corner[a];
        for (int k = 0; k < D; ++k) {
          pic[k] = pic[k] + w[a] * v_new(i, k);
          dv[k] = dv[k] + w[a] * (v_new(i, k) - v_old(i, k));
        }
        pp += w[a] * p_node(i);
      }
    }
    if (correct) {
      std::array<double, D> normal, tangent;
      std::array<index_t, D> nlo, tlo, thi;
      face_samples<D>(g, View<const double, 2>(x), p, normal, nlo, tangent, tlo, thi);
      for (int k = 0; k < D; ++k)
        disp[k] = face_displacement<D>(g, k, faces[k], normal, nlo, tangent, tlo, thi);
    }
    for (int k = 0; k < D; ++k) {
      v(p, k) = blend(apic, v(p, k), dv[k], pic[k]);
      x(p, k) += dt * pic[k];
      if (correct) x(p, k) += disp[k];
    }
    pressure(p) = pp;
    if (g.any_periodic) wrap_periodic<D>(g, x, p);
    if (outlets.any() &&
        beyond_outlet<D>(View<const double, 2>(x), p, lower, upper, outlets.side)) {
      outlets.mass(p) = 0.0;
      outlets.volume(p) = 0.0;
      pressure(p) = 0.0;
      for (int k = 0; k < D; ++k) {
        v(p, k) = 0.0;
        if (apic)
          for (int j = 0; j < D; ++j) affine(p, k, j) = 0.0;
      }
      put_inside<D>(x, v, p, lower, upper, margin);
      return false;
    }
    return put_inside<D>(x, v, p, lower, upper, margin);
  }
};

// The pressure noise (state.pressure_noise: the RMS over particles of p_p minus the
// mass-weighted grid-smoothed pressure at x_p, Pa) in two halves, so that particles held in
// parts (one per MPI rank) add up the first's sums: the particle-to-grid sums of m_p and
// m_p p_p into work_m, work_mp (periodic images folded; the particles grouped by cell,
// cell c holding order[start[c]:start[c + 1]], as counting_sort gives them, and summed cell
// by cell over strips of cell slabs); then the sum over the particles of (p_p -
// smoothed)^2 (Pa^2) from those sums. The smoothed field is the sum of m_p p_p over
// the nodal mass, interpolated back: a smooth pressure field is kept (up to
// interpolation), a checkerboard is not.
template <int D>
void scatter_mass_pressure(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                           View<const double> pressure, View<const index_t> order,
                           View<const index_t> start, View<double> work_m, View<double> work_mp);
template <int D>
double pressure_deviation(const Grid<D>& g, View<const double, 2> x, View<const double> pressure,
                          View<const double> work_m, View<const double> work_mp);

// Lumped nodal mass M_i = sum_p N_i(x_p) m_p (kg), momentum sum_p N_i m_p v_p, material
// volume sum_p N_i V_p (m^3), velocity v_old_i = momentum / M_i and the predictor without
// pressure v_star_i = v_old_i + dt g (eqs. 10-12) where M_i > 0 (both 0 elsewhere); with
// cell_vol non-empty also the particles' volume on the cell centres (scatter_cell_volume).
// With affine non-empty (n x D x D, 1/s: APIC, Jiang et al. 2015) the momentum is
// sum_p N_i m_p (v_p + C_p (x_i - x_p)): the particle's affine velocity field at the node,
// so an affine velocity field carried by the particles reaches every node with mass exactly;
// empty: the FLIP/PIC momentum, unchanged.
// The particles come binned by cell (order, start: see binning.hpp). The slabs of cells
// along the last axis are cut into 2 STRIPS strips of at least 2 slabs holding equal
// numbers of particles (strips.hpp); the even strips are scattered in parallel, then the
// odd ones, so results do not depend on the thread count.
template <int D>
void particles_to_grid(const Grid<D>& g, View<const double, 2> x, View<const double, 2> v,
                       View<const double> mass, View<const double> volume,
                       View<const index_t> order, View<const index_t> start,
                       View<const double> gravity, double dt, View<double> node_mass,
                       View<double, 2> node_mom, View<double> node_vol, View<double, 2> v_old,
                       View<double, 2> v_star, View<double> cell_vol,
                       View<const double, 3> affine = {});

// Eqs. (19)-(21): FLIP/PIC velocity update (flip: the FLIP fraction of this step), position
// update with v^{t+1} evaluated at x_p^t plus the volume correction's displacement (faces:
// one array per axis, see face_displacement; empty arrays: none), pressure; then particles
// that crossed a periodic axis's end are wrapped round it (wrap_periodic) and those that
// left the box [lower, upper] are put back inside (put_inside), or retired where they crossed an
// outlet side (Outlets; retired particles, mass 0, are skipped). Returns how many were put
// back.
// With affine non-empty (n x D x D: APIC) the velocity is instead the PIC velocity
// sum_i N_i(x_p) v_i^{t+1} and C_p = sum_i v_i^{t+1} (grad N_i(x_p))^T, the gradient of the
// same interpolated field (for multilinear N_i this is B_p D_p^-1 of Jiang et al. 2015, exact
// for an affine field); flip and v_old are not used.
template <int D>
index_t grid_to_particles(const Grid<D>& g, View<double, 2> x, View<double, 2> v,
                          View<double> pressure, View<const double, 2> v_old,
                          View<const double, 2> v_new, View<const double> p_node, double dt,
                          double flip, View<const double> lower, View<const double> upper,
                          double margin, const std::array<View<const double>, D>& faces,
                          View<double, 3> affine = {}, const Outlets& outlets = {});

}  // namespace mpmflow
