"""Runs over several processes (MPI; issue 28, docs/design/mpi.md).

``comm``   the processes of a run: mpi4py's world under ``mpirun``, one process without it.
``petsc``  distributed symmetric positive definite solves with PETSc's KSP (conjugate
           gradients preconditioned by GAMG or hypre's BoomerAMG).

mpi4py and petsc4py are imported here only, and only when a run asks for them: the
one-process install (``make setup``) has neither; ``make setup-mpi`` builds the MPI
environment (.venv-mpi).
"""
