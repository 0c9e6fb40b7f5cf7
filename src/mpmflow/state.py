"""The scheme's state and the one door to the compiled core (``mpmflow._core``).

Nothing else in mpmflow imports the core: the rest of the package calls the functions
here, which take NumPy arrays and grids and call the C++ kernels (src/core, one header/
source pair per concept). The core is built once, at install (scikit-build-core, CMake);
nothing compiles at run time.
"""

import numpy as np

from . import _core

CHUNKS = _core.CHUNKS


def max_threads():
    """The threads the core's parallel loops use."""
    return _core.max_threads()


def set_threads(n):
    """Run the core's parallel loops on n threads."""
    _core.set_threads(int(n))
