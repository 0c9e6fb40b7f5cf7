"""Boundaries: the domain's walls and the fixed obstacles, both contact conditions at grid
nodes with a normal and a slip or no-slip condition.

* ``walls``: the wall nodes of the domain, their walls' normals (axis and sign) and
  conditions (``domain.walls``);
* ``obstacles``: obstacles from the signed distance of their shapes at the nodes: cut
  cells' integrals and fluid fractions, obstacle nodes with their normals and conditions
  (``obstacles.N.walls``).

The core applies both (src/core/walls, src/core/cut_cells); no other Python module decides
where a boundary is, which way it faces or whether it holds the material.
"""
