# femcheck — every target creates .venv and installs the project if needed (fresh clone: Python 3.11 + pip).
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
CASE   ?= cases/haptic_6psu.toml
export MPLBACKEND := Agg
export PYVISTA_OFF_SCREEN := true
# tiny dense BLAS calls on 2 shared cores: spinning BLAS threads cost more than they give (measured: Hertz bench 17.5 s -> 8.4 s)
export OPENBLAS_NUM_THREADS ?= 1

.PHONY: venv verify test test-all bench validation sweep clean

venv: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	-$(PY) -m pip install --quiet 'pypardiso>=0.4'
	$(PY) -m femcheck.parallel.precompile
	touch $(STAMP)

## Main job on the reference case: analytical (and FE, where available) verification tables under reports/verify/
verify: $(STAMP)
	$(PY) -m femcheck verify $(CASE) --out reports/verify --check

## Default test suite (CI): everything not marked slow, in TEST_JOBS processes (pytest-xdist; 2 = the CI machine's
## cores, each process peaks at about 2.3 GB); TEST_JOBS=0 runs it in this process
TEST_JOBS ?= 2
test: $(STAMP)
	$(PY) -m pytest -m "not slow" -q -n $(TEST_JOBS)

## Whole test suite including the slow FE cases
test-all: $(STAMP)
	$(PY) -m pytest -q

## Throughput and solve-time measurements -> reports/bench/<area>.json (area calculix: side by side with CalculiX when ccx is on PATH, optional);
## AREA=verify (or any area names, space-separated) runs only those: make bench AREA=verify times the install, cold/warm/no-MKL make verify and make test on a fresh clone (~15 min idle)
AREA ?=
bench: $(STAMP)
	$(PY) -m femcheck.bench --snapshot $(AREA)

## docs/validation.md from the committed bench figures reports/bench/*.json (make bench also rewrites it)
validation: $(STAMP)
	$(PY) -m femcheck.bench.validation_page

## Example parameter sweep on the reference case (Sobol' design, detailed model) -> reports/sweep/reference/
sweep: $(STAMP)
	$(PY) -m femcheck sweep $(CASE) --param guideway.width_radial_m=0.010:0.020 \
		--param guideway.depth_tangential_m=0.008:0.014 --param proximal_link.outer_diameter_m=0.0055:0.009 \
		--param actuation.cable_diameter_m=0.0008:0.0015 --param spherical_joint.ball_radius_m=0.0025:0.005 \
		--design sobol --samples 1024 --model detailed --out reports/sweep/reference --resume

clean:
	rm -rf $(VENV) .pytest_cache build *.egg-info
