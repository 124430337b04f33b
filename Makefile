# Two entry points for a fresh machine (see README): `make figures` and `make test`.
# Both install the package into the active virtual environment, or into a local
# .venv when none is active.

PYTHON ?= python3
ifdef VIRTUAL_ENV
ENV_DIR := $(VIRTUAL_ENV)
else
ENV_DIR := .venv
endif
PY := $(ENV_DIR)/bin/python
INSTALLED := $(ENV_DIR)/.dynia-installed

# Every target runs on every core without the user asking for it (`make figures` renders the reports side by side),
# each target's output printed whole when it ends so that the reports' logs do not interleave.
CORES := $(shell nproc 2>/dev/null || echo 2)
MAKEFLAGS += --jobs=$(CORES) --output-sync=target

PACKAGE := $(wildcard dynia/*.py dynia/*/*.py)
NOTEBOOKS := $(wildcard notebooks/*.py)
# The reports that take longest start first, so that the cores are not left to one long report at the end.
SLOWEST_FIRST := ch5_sampling_benchmark ch4_reidentification ch3_case_study_thesis_code ch4_window_and_complexity \
	ch5_nonlinear_models ch3_case_study logging_system
REPORTS := $(patsubst notebooks/%.py,reports/%.html,$(NOTEBOOKS))
# The chapter-3 notebooks once more with code_path "thesis", each identifiability figure drawn as the
# thesis's code draws it: reports/NAME_thesis_code.html, its figures in reports/figures/thesis_code/.
THESIS_CODE_REPORTS := $(patsubst %,reports/%_thesis_code.html,ch3_example1 ch3_example2 ch3_case_study)
# Notebook parameters: override with `make figures PARAMS=my.yaml` (or one
# report: `make reports/ch3_example1.html PARAMS=my.yaml`). reports/.params
# records which parameters the reports were made with, and is rewritten only
# when that changes, so a change of parameters redoes the reports.
PARAMS ?=
PARAMS_FLAG := $(if $(PARAMS),-f $(PARAMS),)
PARAMS_ID := $(PARAMS) $(if $(PARAMS),$(shell md5sum < $(PARAMS)),defaults)
$(shell mkdir -p reports && echo '$(PARAMS_ID)' | cmp -s - reports/.params || echo '$(PARAMS_ID)' > reports/.params)

# The environment of every executed notebook (no progress bars; results independent of the CPU): see the file.
NOTEBOOK_ENV := $(shell sed -e '/^\#/d' -e '/^$$/d' tests/notebook.env)

# Reference runs of every notebook with the small CI parameters: committed, and
# re-executed by `make test` (nbval), which compares the cells marked
# NBVAL_CHECK_OUTPUT and checks that their code matches notebooks/.
REFERENCES := $(patsubst notebooks/%.py,tests/notebooks/%.ipynb,$(NOTEBOOKS))

.PHONY: install test pytest check-wheel docs bench figures references clean

install: $(INSTALLED)

# uv installs the package and its 120-odd dependencies in about 30 s where pip took 90 s on a fresh clone (the same
# versions); it is itself one wheel that pip installs in a few seconds. --compile-bytecode, as pip does by default:
# where PYTHONDONTWRITEBYTECODE is set (as on CI machines) nothing would write the bytecode later, and every process
# of the suite would compile numpy's and scipy's modules afresh (imports twice as slow, the suite two minutes longer).
$(INSTALLED): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(ENV_DIR)
	$(PY) -m pip install --quiet uv
	$(PY) -m uv pip install --quiet --compile-bytecode --python $(PY) -e ".[dev]"
	touch $@

# The suite (on every core: -n auto in pyproject.toml), the docs and the wheel side by side, not one after another:
# the docs and the wheel (its build, install and first run, which compiles the kernels afresh) share the cores with
# the suite and fill them where it leaves one idle, at its start and its end. Each one's output is printed whole when
# it ends (--output-sync), and any one failing fails the target.
test: $(INSTALLED)
	$(PY) -m ruff check dynia tests notebooks benchmarks
	$(PY) -m ruff format --check dynia tests benchmarks
	$(MAKE) --no-print-directory -j3 --output-sync=target pytest docs check-wheel

# pytest runs with a throwaway PostgreSQL server, started and stopped by .ci/with-postgres (its URL in
# DYNIA_TEST_POSTGRES_URL; a server named there already is used instead). Its binaries: apt-get install postgresql.
# One BLAS thread a process: every pytest-xdist worker already has a core of its own, and OpenBLAS threads that wait
# for a core another worker holds made the small matrices of the models (scipy's expm of a TransferFunction, the
# fits) up to 40 times slower on a busy machine; tests/test_fast.py and the model tests took 136 s instead of 76 s.
# The notebooks run so already (tests/notebook.env).
pytest: $(INSTALLED)
	OPENBLAS_NUM_THREADS=1 .ci/with-postgres $(PY) -m pytest

# The wheel a user installs, used from outside the checkout (see .ci/check-wheel).
check-wheel: $(INSTALLED)
	.ci/check-wheel $(PY)

# The API reference from the docstrings, into docs/_build/html. Nitpicky (-n) with warnings as errors (-W):
# a reference to a module or function that no longer exists fails it. -E reads every page afresh, so that a
# second run reports the warnings of pages Sphinx would otherwise not reread.
docs: $(INSTALLED)
	$(PY) -m sphinx -E -n -W --keep-going -b html docs docs/_build/html

bench: $(INSTALLED)
	$(PY) -m benchmarks.bench

figures: $(foreach name,$(SLOWEST_FIRST),$(filter reports/$(name).html,$(REPORTS) $(THESIS_CODE_REPORTS))) \
	$(REPORTS) $(THESIS_CODE_REPORTS)

# Executed notebook and its HTML (input cells hidden) are redone only when the
# notebook, the package or the parameter file changed.
reports/%.html: notebooks/%.py $(PACKAGE) reports/.params $(INSTALLED) tests/notebook.env
	mkdir -p reports/figures
	$(PY) -m jupytext --to ipynb --output reports/$*.source.ipynb $<
	env $(NOTEBOOK_ENV) $(PY) -m papermill --cwd reports --kernel python3 $(PARAMS_FLAG) reports/$*.source.ipynb reports/$*.ipynb
	rm reports/$*.source.ipynb
	$(PY) -m jupyter nbconvert --to html --no-input --output $*.html reports/$*.ipynb

$(THESIS_CODE_REPORTS): reports/%_thesis_code.html: notebooks/%.py $(PACKAGE) reports/.params $(INSTALLED) tests/notebook.env
	mkdir -p reports/figures/thesis_code
	$(PY) -m jupytext --to ipynb --output reports/$*_thesis_code.source.ipynb $<
	env $(NOTEBOOK_ENV) $(PY) -m papermill --cwd reports --kernel python3 $(PARAMS_FLAG) -p code_path thesis -p figure_dir figures/thesis_code \
		reports/$*_thesis_code.source.ipynb reports/$*_thesis_code.ipynb
	rm reports/$*_thesis_code.source.ipynb
	$(PY) -m jupyter nbconvert --to html --no-input --output $*_thesis_code.html reports/$*_thesis_code.ipynb

references: $(REFERENCES)

tests/notebooks/%.ipynb: notebooks/%.py tests/notebook_params/%.yaml $(PACKAGE) $(INSTALLED) tests/notebook.env
	mkdir -p tests/notebooks
	$(PY) -m jupytext --to ipynb --output tests/notebooks/$*.source.ipynb $<
	env $(NOTEBOOK_ENV) $(PY) -m papermill --cwd tests/notebooks --kernel python3 -f tests/notebook_params/$*.yaml tests/notebooks/$*.source.ipynb $@
	rm tests/notebooks/$*.source.ipynb
	$(PY) tests/keep_checked_outputs.py $@

clean:
	rm -rf reports/*.ipynb reports/*.html
