import numpy as np
from mpi4py import MPI

c = MPI.COMM_WORLD
x = np.array([c.rank + 1.0])
s = np.zeros(1)
c.Allreduce(x, s)
print(f"rank {c.rank}/{c.size} lib={MPI.Get_library_version().splitlines()[0][:60]!r} sum={s[0]}")
