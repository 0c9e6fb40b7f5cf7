#include "../walls.hpp"

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_walls(nb::module_& m) {
  m.def(
      "wall_pair_count",
      [](std::vector<index_t> cells, std::vector<bool> periodic) {
        return with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          return wall_pair_count<D>(make_grid<D>(1.0, cells, periodic));
        });
      },
      "The number of (node, wall) pairs of the grid (none across a periodic axis).");
  m.def(
      "wall_pairs",
      [](std::vector<index_t> cells, std::vector<bool> periodic, Array<index_t> node,
         Array<index_t> axis, Array<double> sign) {
        return with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          const Grid<D> g = make_grid<D>(1.0, cells, periodic);
          if (static_cast<index_t>(node.shape(0)) < wall_pair_count<D>(g) ||
              axis.shape(0) != node.shape(0) || sign.shape(0) != node.shape(0))
            throw std::invalid_argument("wall_pairs: arrays shorter than wall_pair_count");
          return wall_pairs<D>(g, view<index_t>(node, "node"), view<index_t>(axis, "axis"),
                               view<double>(sign, "sign"));
        });
      },
      "The (node, axis, sign) of every wall node and wall, into the arrays; returns how many.");
  m.def(
      "apply_walls",
      [](Array<const index_t> node, Array<const index_t> axis, Array<const double> sign,
         Array<const bool> no_slip, Array<double> v, Array<const bool> contact) {
        if (no_slip.shape(0) != node.shape(0))
          throw std::invalid_argument("apply_walls: no_slip needs one flag per wall pair");
        apply_walls(view<const index_t>(node, "node"), view<const index_t>(axis, "axis"),
                    view<const double>(sign, "sign"), view<const bool>(no_slip, "no_slip"),
                    view<double, 2>(v, "v"), view<const bool, 2>(contact, "contact"));
      },
      "Velocity conditions at the wall nodes (in place).");
  m.def(
      "start_contact",
      [](Array<const index_t> node, Array<const index_t> axis, Array<const double> sign,
         Array<const double> vstar, Array<const index_t> node_row, Array<bool> contact) {
        start_contact(view<const index_t>(node, "node"), view<const index_t>(axis, "axis"),
                      view<const double>(sign, "sign"), view<const double, 2>(vstar, "vstar"),
                      view<const index_t>(node_row, "node_row"), view<bool, 2>(contact, "contact"));
      },
      "The wall nodes in contact as the pressure step starts (in place).");
  m.def(
      "release_contact",
      [](Array<const index_t> node, Array<const index_t> axis, Array<const double> sign,
         Array<const double> vstar, Array<const index_t> node_row, Array<const double> p_node,
         Array<bool> contact) {
        return release_contact(
            view<const index_t>(node, "node"), view<const index_t>(axis, "axis"),
            view<const double>(sign, "sign"), view<const double, 2>(vstar, "vstar"),
            view<const index_t>(node_row, "node_row"), view<const double>(p_node, "p_node"),
            view<bool, 2>(contact, "contact"));
      },
      "Release the wall nodes under tension that v* leaves; returns how many.");
  m.def(
      "apply_obstacles",
      [](Array<const index_t> onode, Array<const double> onormal, Array<const bool> no_slip,
         Array<double> v, Array<const bool> ocontact) {
        apply_obstacles(view<const index_t>(onode, "onode"),
                        view<const double, 2>(onormal, "onormal"),
                        view<const bool>(no_slip, "no_slip"), view<double, 2>(v, "v"),
                        view<const bool>(ocontact, "ocontact"));
      },
      "Velocity conditions at the obstacle nodes (in place).");
  m.def(
      "start_obstacles",
      [](Array<const index_t> onode, Array<const double> onormal, Array<const double> vstar,
         Array<const index_t> node_row, Array<bool> ocontact) {
        start_obstacles(
            view<const index_t>(onode, "onode"), view<const double, 2>(onormal, "onormal"),
            view<const double, 2>(vstar, "vstar"), view<const index_t>(node_row, "node_row"),
            view<bool>(ocontact, "ocontact"));
      },
      "The obstacle nodes in contact as the pressure step starts (in place).");
  m.def(
      "release_obstacles",
      [](Array<const index_t> onode, Array<const double> onormal, Array<const double> vstar,
         Array<const index_t> node_row, Array<const double> p_node, Array<bool> ocontact) {
        return release_obstacles(
            view<const index_t>(onode, "onode"), view<const double, 2>(onormal, "onormal"),
            view<const double, 2>(vstar, "vstar"), view<const index_t>(node_row, "node_row"),
            view<const double>(p_node, "p_node"), view<bool>(ocontact, "ocontact"));
      },
      "Release the obstacle nodes under tension that v* leaves; returns how many.");
}

}  // namespace mpmflow::bind
