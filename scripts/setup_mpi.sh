#!/usr/bin/env bash
# The MPI environment (issue 28; docs/design/mpi.md section 1): `make setup-mpi` runs this.
#
#   scripts/setup_mpi.sh PYTHON VENV
#
# PETSc has no wheels on PyPI (a source build takes about an hour on 2 cores), so PETSc,
# petsc4py, Open MPI and mpi4py come from Debian's packages (python3-petsc4py 3.18 with
# hypre and MUMPS, python3-mpi4py, openmpi-bin). Debian's petsc4py is built against numpy
# 1.x and refuses numpy 2, so the MPI runs get their own virtual environment (VENV) with
# numpy < 2, which reaches Debian's two packages through a .pth file; the one-process
# environment (.venv, numpy 2) stays free of MPI. The core is built again for VENV in its
# own build folder (build/mpi-<tag>), so that the two environments never rebuild each
# other's.
set -euo pipefail
PYTHON=${1:-python3}
VENV=${2:-.venv-mpi}
PETSC4PY=/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real/lib/python3/dist-packages/petsc4py
MPI4PY=/usr/lib/python3/dist-packages/mpi4py

if [ ! -d "$PETSC4PY" ] || [ ! -d "$MPI4PY" ] || ! command -v mpirun >/dev/null; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "installing Open MPI, mpi4py and petsc4py from Debian's packages"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      openmpi-bin python3-mpi4py python3-petsc4py >/dev/null
  else
    echo "setup-mpi needs Debian's packages openmpi-bin, python3-mpi4py and python3-petsc4py:" >&2
    echo "  sudo apt-get install --no-install-recommends openmpi-bin python3-mpi4py python3-petsc4py" >&2
    exit 2
  fi
fi

test -d "$VENV" || "$PYTHON" -m venv "$VENV"
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet "numpy<2" "scikit-build-core>=0.10" "nanobind>=2.4" \
  "cmake>=3.18" ninja
# Debian's mpi4py and petsc4py, and nothing else of Debian's Python, on the venv's path
SITE=$("$VENV/bin/python" -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")
mkdir -p "$VENV/debian"
ln -sfn "$MPI4PY" "$VENV/debian/mpi4py"
ln -sfn "$PETSC4PY" "$VENV/debian/petsc4py"
echo "$(cd "$VENV/debian" && pwd)" >"$SITE/debian-mpi.pth"
echo "building the core for $VENV (about a minute on 2 cores the first time)"
TAG=$("$VENV/bin/python" -c "import sys; print(f'cp{sys.version_info[0]}{sys.version_info[1]}')")
"$VENV/bin/python" -m pip install --quiet --no-build-isolation \
  -C "build-dir=build/mpi-$TAG" -e ".[test]"
"$VENV/bin/python" -c "import petsc4py, mpi4py, numpy; petsc4py.init(); from petsc4py import PETSc; \
print(f'MPI environment: numpy {numpy.__version__}, petsc4py {petsc4py.__version__}, mpi4py {mpi4py.__version__}')"
