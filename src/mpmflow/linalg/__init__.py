"""Linear solvers: ``solvers`` (conjugate gradients with the core's geometric multigrid,
pyamg's algebraic multigrid, or a sparse direct solve) for the pressure system."""
