# Thin front end to CMake. `make test` and `make reproduce` are the README's two commands.
BUILD ?= build
JOBS  ?= 2
OUT   ?= $(CURDIR)/out
# Extra CMake arguments for the Release build, e.g. CMAKE_ARGS=-DWBM_WERROR=ON (.ci/run).
CMAKE_ARGS ?=
# Ninja for a new build tree (CMake reads CMAKE_GENERATOR when it first configures a tree; a tree
# configured before keeps its generator, and a CMAKE_GENERATOR in the environment wins). Make
# builds a target only after the targets it links have linked, so on 2 cores the last unity unit
# of wbm_solvers or wbm_scene compiled alone while the tests waited; Ninja starts a target's
# compiles at once and waits only to link. Measured on 2 cores (stop 61): the sanitizer build
# about 1080 -> 852 and 949 s (two runs), the Release build 955 -> 771 s (the tests passed
# alike). Ninja starts ready commands in the order of build.ninja, which is the order of
# definition: the reproductions still start longest first.
export CMAKE_GENERATOR ?= Ninja

.PHONY: deps configure build test sanitize-configure check-sanitize check-fuzz reproduce bench clean

deps:
	@./scripts/install-deps

configure: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DWBM_OUT_DIR=$(OUT) $(CMAKE_ARGS) > $(BUILD).configure.log 2>&1 \
	  || { cat $(BUILD).configure.log; exit 1; }

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

test: build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# One instrumented build, $(SANITIZE_BUILD)/, serves check-sanitize and check-fuzz: clang-14
# (scripts/install-deps fuzz), Debug (assertions on: Eigen's range and size checks are active) at
# -O1 -g1, -fsanitize=address,undefined with -fno-sanitize-recover=all (any report fails the run);
# libFuzzer's coverage on the parser libraries only (tests/fuzz/CMakeLists.txt), so that the fuzz
# targets link against the same libraries. Executables link clang's shared ASan runtime
# (-shared-libasan, found by rpath): the pytest suite preloads that runtime into the interpreter,
# and the `wbm` it starts must use the same one ("incompatible ASan runtimes" otherwise). -g1
# (functions and line tables: what a sanitizer's stack trace prints) instead of -g. The libraries
# and tools are a unity build (CMAKE_UNITY_BUILD: 8 sources a unit, each header parsed and each
# Eigen template instantiated once per unit: wbm_solvers 261 s of CPU instead of 524 s), and since
# stop 60 the tests too, as in every build (top CMakeLists.txt). No reproductions or benchmarks:
# they stay in `make test`.
# Measured on 2 cores (stop 49), one sanitized test file (test_continuation.cpp): g++ 95.6 s,
# clang 55.9 s, clang with libFuzzer's coverage 67.3 s. Before, a g++ build for the sanitizers
# (about 19 min) and a clang build for the fuzzers (about 5.5 min); now the one build 882 s. With
# the coverage on every library the sanitized tests took 499 s, on the parser libraries 302 s.
SANITIZE_BUILD ?= build-sanitize
SANITIZE_CXX   ?= clang++-14
SANITIZE_FLAGS  = -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
SANITIZE_LINK   = -fsanitize=address,undefined -shared-libasan
SANITIZE_RT     = $$($(SANITIZE_CXX) -print-file-name=libclang_rt.asan-x86_64.so)
sanitize-configure:
	@./scripts/install-deps fuzz
	@command -v $(SANITIZE_CXX) > /dev/null || { echo "check-sanitize: $(SANITIZE_CXX) not found: run scripts/install-deps fuzz"; exit 1; }
	@cmake -S . -B $(SANITIZE_BUILD) -DCMAKE_CXX_COMPILER=$(SANITIZE_CXX) -DCMAKE_BUILD_TYPE=Debug \
	  -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DCMAKE_UNITY_BUILD=ON -DCMAKE_CXX_FLAGS="$(SANITIZE_FLAGS)" \
	  -DCMAKE_EXE_LINKER_FLAGS="$(SANITIZE_LINK) -Wl,-rpath,$$(dirname $(SANITIZE_RT))" \
	  -DCMAKE_MODULE_LINKER_FLAGS="-fsanitize=address,undefined" -DWBM_BUILD_FUZZ=ON -DWBM_BUILD_REPRODUCE=OFF \
	  -DWBM_BUILD_BENCH=OFF -DWBM_OUT_DIR=$(CURDIR)/$(SANITIZE_BUILD)/out > $(SANITIZE_BUILD).configure.log 2>&1 \
	  || { cat $(SANITIZE_BUILD).configure.log; exit 1; }

# Unit, scene and Python tests (tests/python, Hypothesis included, on the sanitized module with the
# interpreter CMake found) with leak detection. The benchmarks, the reproduce executables'
# --quick runs and the install test are left to `make test`.
# SANITIZE_SKIP: the tests left to `make test` (Release), by name. Each repeats the LL11 backbone
# continuation that shorter tests (BackbonePiecesAreSmoothAndTheirEventsMatchTheMin,
# StopAlongADirectionIsAChangeOfCoordinates, the scene's nnm runs) put through the same code
# under the sanitizers; several times over (five rounding perturbations, three N x m pairs,
# Alg. 1 against the KKT continuation) it took, measured under ASan + UBSan at -O1 (stop 48, g++,
# ctest -j 2): 346, 246, 147, 116 and 99 s, 954 s of the suite's 2499 s. Four more (stop 60, to
# keep CI under 50 min), each the longest of its group and a repetition of what the group's shorter tests run under the sanitizers: the plastic impact
# oscillator's convergence study over step sizes (MoreauJean: RigidStopConvergesAtFirstOrderInTheStep,
# EnergyBalanceClosesOverAPeriod), the friction normal load's convergence to time stepping
# (FrictionNormalLoad.JacobianMatchesCentralDifferences, CentralDifferencesAgreeWithBdfWithoutFriction,
# SceneFrictionNormalLoad.ASolveBalancesEnergyAndKeepsCoulombsBound) and two example scenes that
# tests run in smaller form (scene.friction_normal_load; scene.rod_continuation:
# Scene.StiffStopContinuationRunsWithDefaults, StiffStopWithThePapersFourierBasisCompletes): 67, 41, 73, 46 s
# under ASan + UBSan (clang -O1, ctest -j 2), 227 s of the suite's 947 s. Three more (stop 61,
# 178 s of the remaining 720 s): TwinSamplesWhoseMultipliersAreIllDeterminedSwitchTogether (87 s,
# five backbones of the LL11 rod under rounding perturbations: the continuation is the one above)
# and the example scenes friction_damper and friction_damper_coulomb (45 and 46 s; their analyses
# run under the sanitizers in SceneFriction.TheDamperPeakIsTheFirstHarmonicEnergyBalance and
# SceneFriction.TheExactCoulombDamperPeakIsTheFirstHarmonicEnergyBalance, the CLI's writing in the
# other scene.* runs). Three more (stop 65, 37 s of the remaining 267 s, measured on a faster
# machine than CI's; stop 64's CI took 3074 s), each a comparison of two whole paths at full size
# whose code shorter tests put through the sanitizers: BorderedWoodbury.ForcedResponseBranchesEqualTheDensePath
# (15 s; the bordered Woodbury in RepresentsTheBorderedMatrixAndSolvesItAsADenseLu,
# SolvesAtAFoldWhereTheJacobianIsSingular and every forced-response continuation of the scene
# tests), ContactDirection.ANormalContactEqualsTheTransformedWallContact (13 s, 300 periods of
# Moreau–Jean at 4096 steps a period; a contact along a direction in AStopOnTheNegativeSideMirrorsThePositiveOne,
# Moreau–Jean on relative contact in RelativeContact.TimeSteppingEqualsTheTransformedObstacleProblem),
# RelativeContact.WeightedResidualEqualsTheTransformedObstacleProblem (9 s; JacobianMatchesFiniteDifferences
# and FloquetMultipliersEqualThoseOfTheTransformedProblem run the same residual).
# Stop 76: ImpactShooting.MoreauJeanWithRestitutionConvergesToTheClosedFormOrbit, the restitution
# analogue of the plastic oscillator's study above (1.4 s in Release; Newton's law with e > 0 runs
# under the sanitizers in MoreauJean.EnergyBalanceClosesOverAPeriod, e = 1).
# Stop 67: three Moreau–Jean friction tests that run hundreds of periods through Siconos (29, 16
# and 19 s under ASan + UBSan, against 3.7, 1.8 and 2.0 s in Release):
# MoreauJeanFriction.(TendsToDenHartogsDampedSteadyState|RigidNormalUnderAStaticLoadActsAsAConstantNormalLoad|
# JenkinsOnAPenaltyNormalTendsToCoulombSignoriniUnderAVaryingLoad). The same fc2d path, with a
# frictionless stop and a Coulomb contact in one problem, goes through the sanitizers in
# AFrictionlessStopThroughSiconosEqualsTheProjectedGaussSeidelPath (1 s), and the 2D contact under
# a varying normal load in SceneFriction.TimeSteppingWithARigidNormalContactBalancesItsEnergy.
# Stop 77: the example scene rod_rigid_stop_continuation (41 s under ASan + UBSan, with another
# build beside it): its rigid-stop stability runs under the sanitizers in
# Scene.RigidStopContinuationGivesTheExactOrbitsStability and the ImpactStability tests.
# Stop 78: FrictionRigidNormal.ConvergesToMoreauJeanUnderAVaryingNormalLoad (6.8 s in Release: a
# Moreau–Jean reference at T/16384 and six solves up to 512 impulses); the 2D contact's residual,
# Jacobian and full-step active set run under the sanitizers in the other FrictionRigidNormal tests
# and SceneFriction.ASolveOfA2DContactBalancesItsEnergyAndMatchesTimeStepping.
# Stop 80: MovingObstacle.HarmonicBalanceConvergesToCentralDifferences (8.8 s in Release, 129 s
# under ASan + UBSan beside another build: three harmonic-balance solves up to H = 192 with the
# cell-average rule); the cell-average slope relative to a moving surface runs under the
# sanitizers in MovingObstacle.AMovingObstacleIsAChangeOfCoordinates, and central differences
# with a moving surface in the same test's Release run only (the four lines of their contact
# update).
# Stop 82: CirculantBlocks.JenkinsDamperBranchCrossesItsResonanceInDb6 (2 s in Release, 39 s
# under ASan + UBSan: 5 800 continuation points of a Jenkins damper); the circulant blocks run
# under the sanitizers in CirculantBlocks.ContactResidualIsSmoothInTheFrequencyNearResonance, the
# Jenkins law's continuation in the other friction tests.
# `make check-sanitize SANITIZE_SKIP=` runs them all.
SANITIZE_SKIP  ?= NonlinearModes\.(BackboneThroughItsCornersDoesNotDependOnRounding|BackboneEntersAnIllConditionedPieceWithoutTurningBack|AugmentedLagrangianAndKktContinuationAgree|AboveContactConstraintsHoldAndFrequencyHardens)|Continuation\.ExtremesCompleteOrStopWithAReasonAndValidPoints|MoreauJean\.PlasticImpactOscillatorConvergesToTheClosedFormOrbit|ImpactShooting\.MoreauJeanWithRestitutionConvergesToTheClosedFormOrbit|FrictionNormalLoad\.WeightedResidualConvergesToTheTimeSteppingReference|NonlinearModes\.TwinSamplesWhoseMultipliersAreIllDeterminedSwitchTogether|scene\.(friction_normal_load|rod_continuation|friction_damper|friction_damper_coulomb|rod_rigid_stop_continuation)$$|BorderedWoodbury\.ForcedResponseBranchesEqualTheDensePath|ContactDirection\.ANormalContactEqualsTheTransformedWallContact|RelativeContact\.WeightedResidualEqualsTheTransformedObstacleProblem|MoreauJeanFriction\.(TendsToDenHartogsDampedSteadyState|RigidNormalUnderAStaticLoadActsAsAConstantNormalLoad|JenkinsOnAPenaltyNormalTendsToCoulombSignoriniUnderAVaryingLoad)|FrictionRigidNormal\.ConvergesToMoreauJeanUnderAVaryingNormalLoad|MovingObstacle\.HarmonicBalanceConvergesToCentralDifferences|CirculantBlocks\.JenkinsDamperBranchCrossesItsResonanceInDb6
# SANITIZE_PYTEST_SKIP: Python tests left to `make test`, by test function name (pytest -k). The
# two Dask-process tests of tests/python/test_study.py (issue #37) run twelve and eight rod continuations through the
# sanitized `wbm run` (148 and 81 s under ASan + UBSan, stop 66, against 16 s in Release): the
# sanitizers see nothing there that test_a_linear_study_gives_the_closed_form_peak (the same
# `wbm study` path, the binding's scene_json(dict, file), a LocalCluster, `wbm run` of a sweep: 2 s)
# and the C++ tests of continuation do not. `make check-sanitize SANITIZE_PYTEST_SKIP=` runs them.
empty :=
space := $(empty) $(empty)
SANITIZE_PYTEST_SKIP ?= test_a_scheduler_and_two_workers_finish_a_study_when_one_worker_is_killed \
  test_an_interrupted_study_resumes_without_recomputing
check-sanitize: sanitize-configure
	@cmake --build $(SANITIZE_BUILD) -j $(JOBS) --target test_wavelets test_spectral test_fem test_contact \
	  test_solvers test_scene wbm wbm_python
	@cd $(SANITIZE_BUILD) && ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS) -L 'wavelets|spectral|fem|contact|solvers|scene' \
	    $(if $(SANITIZE_SKIP),-E '$(SANITIZE_SKIP)')
	@# The pytest suite (Hypothesis included) on the sanitized module: the interpreter is not
	@# instrumented, so clang's shared ASan runtime (which holds UBSan's handlers) is preloaded;
	@# CPython's own allocations at exit are not leaks of ours (detect_leaks=0).
	@cd $(SANITIZE_BUILD) && LD_PRELOAD="$(SANITIZE_RT)" \
	  ASAN_OPTIONS=detect_leaks=0:halt_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  PYTHONPATH=$(CURDIR)/$(SANITIZE_BUILD)/python WBM_CLI=$(CURDIR)/$(SANITIZE_BUILD)/cli/wbm PYTHONDONTWRITEBYTECODE=1 \
	  "$$(sed -n 's/^Python3_EXECUTABLE:FILEPATH=//p' CMakeCache.txt)" -m pytest -q -p no:cacheprovider $(CURDIR)/tests/python \
	  $(if $(strip $(SANITIZE_PYTEST_SKIP)),-k 'not ($(subst $(space), or ,$(strip $(SANITIZE_PYTEST_SKIP))))')

# libFuzzer on the scene parser and the Matrix Market reader, each for FUZZ_SECONDS, in the
# sanitized build above (after check-sanitize, only the two targets are new); seeds are our own
# scenes and matrices, copied into a fresh corpus so that the source tree is never written. A
# crash, a sanitizer report, a timeout (10 s per input) or more than 2 GB of memory fails the run
# and leaves the input in $(SANITIZE_BUILD)/findings/. Prints each target's executions. The two
# targets run at once, one a core (libFuzzer runs one process each): the same FUZZ_SECONDS each in
# half the wall time (stop 61: 120 -> 60 s of check-fuzz's time).
FUZZ_SECONDS ?= 60
FUZZ_DIR      = $(SANITIZE_BUILD)/fuzz-run
check-fuzz: sanitize-configure
	@cmake --build $(SANITIZE_BUILD) -j $(JOBS) --target fuzz_scene fuzz_matrix_market
	@rm -rf $(FUZZ_DIR) && mkdir -p $(FUZZ_DIR)/corpus/scene $(FUZZ_DIR)/corpus/matrix_market $(FUZZ_DIR)/findings
	@cp reproduce/scenes/*.toml examples/scenes/*.toml $(FUZZ_DIR)/corpus/scene/
	@cp examples/scenes/*.mtx $(FUZZ_DIR)/corpus/matrix_market/
	@pids=""; for t in scene matrix_market; do \
	  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 $(SANITIZE_BUILD)/tests/fuzz/fuzz_$$t \
	    -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
	    -artifact_prefix=$(FUZZ_DIR)/findings/$$t- $(FUZZ_DIR)/corpus/$$t > $(FUZZ_DIR)/fuzz_$$t.log 2>&1 & \
	  pids="$$pids $$!"; \
	done; \
	fail=0; set -- $$pids; for t in scene matrix_market; do \
	  if wait $$1; then \
	    echo "check-fuzz: fuzz_$$t: $$(grep -o 'number_of_executed_units: [0-9]*' $(FUZZ_DIR)/fuzz_$$t.log | grep -o '[0-9]*') executions in $(FUZZ_SECONDS) s, no failure"; \
	  else \
	    tail -60 $(FUZZ_DIR)/fuzz_$$t.log; echo "check-fuzz: fuzz_$$t found a failure (input in $(FUZZ_DIR)/findings/)"; fail=1; \
	  fi; \
	  shift; \
	done; \
	exit $$fail

# The reproduce executables run JOBS at a time (one target each), then plot.py and report.py.
reproduce: build
	@cmake --build $(BUILD) --target reproduce -j $(JOBS)

bench: build
	@cmake --build $(BUILD) --target bench

clean:
	@rm -rf $(BUILD) $(BUILD).configure.log $(SANITIZE_BUILD) $(SANITIZE_BUILD).configure.log
