#!/usr/bin/env bash
# The MPI environment (issue 28; docs/design/mpi.md section 1): `make setup-mpi` runs this.
#
#   scripts/setup_mpi.sh PYTHON VENV [ONE_VENV]
#
# PETSc has no wheels on PyPI (a source build takes about an hour on 2 cores), so PETSc,
# petsc4py, Open MPI and mpi4py come from Debian's packages (python3-petsc4py 3.18 with
# hypre and MUMPS, python3-mpi4py, openmpi-bin). Debian's petsc4py is built against numpy
# 1.x and refuses numpy 2, so the MPI runs get their own virtual environment (VENV) with
# numpy < 2, which reaches Debian's two packages through a .pth file; the one-process
# environment (.venv, numpy 2) stays free of MPI. VENV runs the package from src/ with the
# core that `make setup` built for .venv (a link in src/mpmflow, ignored by git).
set -euo pipefail
PYTHON=${1:-python3}
VENV=${2:-.venv-mpi}
ONE_VENV=${3:-.venv}  # the one-process environment, whose compiled core this one loads
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

CORE=$(ls "$ONE_VENV"/lib/python*/site-packages/mpmflow/_core.*.so 2>/dev/null | head -1)
if [ -z "$CORE" ]; then
  echo "setup-mpi needs the one-process set-up's compiled core: run make setup first" >&2
  exit 2
fi
test -d "$VENV" || "$PYTHON" -m venv "$VENV"
"$VENV/bin/python" -m pip install --quiet --upgrade pip
# the project's dependencies (and its test extra) with numpy < 2, from pyproject.toml
"$ONE_VENV/bin/python" - <<'PY' >"$VENV/requirements.txt"
import sys

if sys.version_info >= (3, 11):
    import tomllib
else:  # a dependency of the package on 3.10
    import tomli as tomllib
project = tomllib.load(open("pyproject.toml", "rb"))["project"]
for line in project["dependencies"] + project["optional-dependencies"]["test"]:
    print(line)
print("numpy<2")
PY
"$VENV/bin/python" -m pip install --quiet -r "$VENV/requirements.txt"
# an installed copy of the package (an earlier set-up built one) would shadow src/ and its core
"$VENV/bin/python" -m pip uninstall --quiet --yes mpmflow 2>/dev/null || true
# Debian's mpi4py and petsc4py, and nothing else of Debian's Python, on the venv's path;
# the package from src/, its compiled core the one-process set-up built (the same
# interpreter; nanobind's extension does not depend on numpy's ABI), so it is not built twice
SITE=$("$VENV/bin/python" -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")
mkdir -p "$VENV/debian"
ln -sfn "$MPI4PY" "$VENV/debian/mpi4py"
ln -sfn "$PETSC4PY" "$VENV/debian/petsc4py"
echo "$(cd "$VENV/debian" && pwd)" >"$SITE/debian-mpi.pth"
echo "$(pwd)/src" >"$SITE/mpmflow-src.pth"
TARGET="$(cd "$(dirname "$CORE")" && pwd)/$(basename "$CORE")"
LINK="src/mpmflow/$(basename "$CORE")"
if [ "$(readlink "$LINK" 2>/dev/null)" != "$TARGET" ]; then
  # the link is no change of the package: the folder keeps its time, or the Makefile would
  # take it for a moved module and install .venv again
  STAMP=$(stat -c %Y src/mpmflow)
  ln -sfn "$TARGET" "$LINK"
  touch -d "@$STAMP" src/mpmflow
fi
cat >"$VENV/bin/mpmflow" <<PY
#!$(cd "$VENV" && pwd)/bin/python
import sys
from mpmflow.cli import main
sys.exit(main())
PY
chmod +x "$VENV/bin/mpmflow"
"$VENV/bin/python" -c "import petsc4py, mpi4py, numpy; petsc4py.init(); from petsc4py import PETSc; \
import mpmflow._core; assert mpmflow._core.__file__.startswith('$(pwd)/src/'), mpmflow._core.__file__; \
print(f'MPI environment: numpy {numpy.__version__}, petsc4py {petsc4py.__version__}, mpi4py {mpi4py.__version__}')"
