#include "walls.hpp"

namespace mpmflow {

template <int D>
index_t wall_pair_count(const Grid<D>& g) {
  index_t total = 0;
  for (int k = 0; k < D; ++k)
    if (!g.periodic[k]) total += 2 * (g.nnodes / (g.cells[k] + 1));
  return total;
}

template <int D>
index_t wall_pairs(const Grid<D>& g, View<index_t> node, View<index_t> axis, View<double> sign) {
  index_t e = 0;
  index_t ix[D];
  for (int k = 0; k < D; ++k)
    for (index_t i = 0; i < g.nnodes; ++i) {
      if (g.periodic[k]) break;  // no wall across a periodic axis
      g.node_coords(i, ix);
      if (ix[k] != 0) continue;
      for (int side = 0; side < 2; ++side) {
        node(e) = i + side * g.cells[k] * g.ns[k];
        axis(e) = k;
        sign(e) = side == 0 ? -1.0 : 1.0;
        ++e;
      }
    }
  return e;
}

void apply_walls(View<const index_t> node, View<const index_t> axis, View<const double> sign,
                 View<const bool> no_slip, View<double, 2> v, View<const bool, 2> contact,
                 View<const double, 2> held) {
  const bool moving = held.size() > 0;
  for (index_t e = 0; e < node.size(); ++e) {
    const index_t i = node(e), k = axis(e);
    if (contact(i, k) || sign(e) * v(i, k) > 0.0) {
      v(i, k) = moving ? held(i, k) : 0.0;
      if (no_slip(e) && contact(i, k))
        for (index_t m = 0; m < v.extent(1); ++m)
          if (m != k) v(i, m) = moving ? held(i, m) : 0.0;
    }
  }
}

void start_contact(View<const index_t> node, View<const index_t> axis, View<const double> sign,
                   View<const double, 2> vstar, View<const index_t> node_row, View<bool, 2> contact,
                   View<const bool> bonded) {
  for (index_t j = 0; j < contact.size(); ++j) contact[j] = false;
  const bool any_bonded = bonded.size() > 0;
  for (index_t e = 0; e < node.size(); ++e) {
    const index_t i = node(e), k = axis(e);
    contact(i, k) = node_row(i) >= 0 || sign(e) * vstar(i, k) > 0.0 || (any_bonded && bonded(e));
  }
}

index_t release_contact(View<const index_t> node, View<const index_t> axis, View<const double> sign,
                        View<const double, 2> vstar, View<const index_t> node_row,
                        View<const double> p_node, View<bool, 2> contact, View<const bool> bonded) {
  index_t released = 0;
  const bool any_bonded = bonded.size() > 0;
  for (index_t e = 0; e < node.size(); ++e) {
    const index_t i = node(e), k = axis(e);
    if (any_bonded && bonded(e)) continue;
    if (node_row(i) >= 0 && p_node(i) < 0.0 && contact(i, k) && sign(e) * vstar(i, k) < 0.0) {
      contact(i, k) = false;
      ++released;
    }
  }
  return released;
}

void contact_rows(View<const index_t> node, View<const index_t> axis, View<const bool> bonded,
                  View<const bool, 2> contact, View<const index_t> onode, View<const bool> ocontact,
                  View<const index_t> node_row, View<bool> candidate) {
  for (index_t r = 0; r < candidate.size(); ++r) candidate(r) = false;
  const bool any_bonded = bonded.size() > 0;
  for (index_t e = 0; e < node.size(); ++e) {
    const index_t i = node(e);
    if (node_row(i) >= 0 && contact(i, axis(e)) && !(any_bonded && bonded(e)))
      candidate(node_row(i)) = true;
  }
  for (index_t e = 0; e < onode.size(); ++e) {
    const index_t i = onode(e);
    if (node_row(i) >= 0 && ocontact(i)) candidate(node_row(i)) = true;
  }
}

index_t release_rows(View<const index_t> node, View<const index_t> axis, View<const bool> bonded,
                     View<const index_t> onode, View<const index_t> node_row, View<const bool> zero,
                     View<bool, 2> contact, View<bool> ocontact) {
  index_t released = 0;
  const bool any_bonded = bonded.size() > 0;
  for (index_t e = 0; e < node.size(); ++e) {
    const index_t i = node(e), k = axis(e);
    if (node_row(i) < 0 || !zero(node_row(i)) || (any_bonded && bonded(e))) continue;
    released += contact(i, k) ? 1 : 0;
    contact(i, k) = false;
  }
  for (index_t e = 0; e < onode.size(); ++e) {
    const index_t i = onode(e);
    if (node_row(i) < 0 || !zero(node_row(i))) continue;
    released += ocontact(i) ? 1 : 0;
    ocontact(i) = false;
  }
  return released;
}

void apply_obstacles(View<const index_t> onode, View<const double, 2> onormal,
                     View<const bool> no_slip, View<double, 2> v, View<const bool> ocontact,
                     View<const double> phi, View<const double, 2> held) {
  const index_t D = v.extent(1);
  const bool in_solid_only = phi.size() > 0, moving = held.size() > 0;
  for (index_t e = 0; e < onode.size(); ++e) {
    const index_t i = onode(e);
    if (in_solid_only && phi(i) > 0.0) continue;
    const double vn = normal_velocity(v, held, i, onormal, e);
    if (ocontact(i) && no_slip(e)) {
      for (index_t k = 0; k < D; ++k) v(i, k) = moving ? held(i, k) : 0.0;
    } else if (ocontact(i) || vn > 0.0) {
      for (index_t k = 0; k < D; ++k) v(i, k) -= vn * onormal(e, k);
    }
  }
}

void start_obstacles(View<const index_t> onode, View<const double, 2> onormal,
                     View<const double, 2> vstar, View<const index_t> node_row, View<bool> ocontact,
                     View<const double, 2> held) {
  for (index_t e = 0; e < onode.size(); ++e) {
    const index_t i = onode(e);
    const double vn = normal_velocity(vstar, held, i, onormal, e);
    ocontact(i) = node_row(i) >= 0 || vn > 0.0;
  }
}

index_t release_obstacles(View<const index_t> onode, View<const double, 2> onormal,
                          View<const double, 2> vstar, View<const index_t> node_row,
                          View<const double> p_node, View<bool> ocontact,
                          View<const double, 2> held) {
  index_t released = 0;
  for (index_t e = 0; e < onode.size(); ++e) {
    const index_t i = onode(e);
    const double vn = normal_velocity(vstar, held, i, onormal, e);
    if (node_row(i) >= 0 && p_node(i) < 0.0 && ocontact(i) && vn < 0.0) {
      ocontact(i) = false;
      ++released;
    }
  }
  return released;
}

template index_t wall_pair_count<2>(const Grid<2>&);
template index_t wall_pair_count<3>(const Grid<3>&);
template index_t wall_pairs<2>(const Grid<2>&, View<index_t>, View<index_t>, View<double>);
template index_t wall_pairs<3>(const Grid<3>&, View<index_t>, View<index_t>, View<double>);

}  // namespace mpmflow
