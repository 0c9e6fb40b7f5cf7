"""Geometry: the shapes of bodies and obstacles and the particles that fill the bodies.

* ``shapes``: solid shapes in 2D and 3D (box, disc, polygon, sphere, cylinder): containment,
  signed distance, bounds, volume, support;
* ``meshes``: closed triangle meshes (``Mesh``) and the reading of STL and OBJ files;
* ``specs``: the shape of a case's ``[[bodies]]`` or ``[[obstacles]]`` table;
* ``lattice``: the global particle lattice every body is filled from;
* ``bodies``: particle counts, overlaps and extents of bodies before any particle exists;
* ``placement``: the case's rules on where bodies and obstacles may stand;
* ``seeding``: the particles of a case (``build_particles``).
"""
