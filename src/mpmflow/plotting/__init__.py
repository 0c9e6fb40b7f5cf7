"""Figures of a run (``mpmflow plot``): ``figures`` (time series, probes, snapshots, the 3D
pictures), ``surface`` (the 3D water's surface: the particles' volume fraction on the grid,
its level set at 1/2 by marching cubes, obstacles as triangles) and ``mpl`` (the one way
mpmflow uses matplotlib: the non-interactive backend, a clear error when it is missing, an
atomic PNG save)."""
