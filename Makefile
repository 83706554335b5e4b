# Thin front end to CMake. `make test` and `make reproduce` are the README's two commands.
BUILD ?= build
JOBS  ?= 2
OUT   ?= $(CURDIR)/out
# Extra CMake arguments for the Release build, e.g. CMAKE_ARGS=-DWBM_WERROR=ON (.ci/run).
CMAKE_ARGS ?=

.PHONY: deps configure build test check-sanitize reproduce bench clean

deps:
	@./scripts/install-deps

configure: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DWBM_OUT_DIR=$(OUT) $(CMAKE_ARGS) > $(BUILD).configure.log 2>&1 \
	  || { cat $(BUILD).configure.log; exit 1; }

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

test: build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# Unit and scene tests under AddressSanitizer and UndefinedBehaviorSanitizer, with assertions on
# (no NDEBUG: Eigen's range and size checks are active). -O1 keeps the run within minutes; any
# report fails the run (halt_on_error, -fno-sanitize-recover). The benchmarks, the reproduce
# executables' --quick runs and the install test are left to `make test`.
SANITIZE_BUILD ?= build-sanitize
SANITIZE_FLAGS  = -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
check-sanitize: deps
	@cmake -S . -B $(SANITIZE_BUILD) -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" \
	  -DCMAKE_CXX_FLAGS="$(SANITIZE_FLAGS)" -DCMAKE_EXE_LINKER_FLAGS="$(SANITIZE_FLAGS)" \
	  -DWBM_OUT_DIR=$(CURDIR)/$(SANITIZE_BUILD)/out > $(SANITIZE_BUILD).configure.log 2>&1 \
	  || { cat $(SANITIZE_BUILD).configure.log; exit 1; }
	@cmake --build $(SANITIZE_BUILD) -j $(JOBS) --target test_wavelets test_spectral test_fem test_contact \
	  test_solvers test_scene wbm
	@cd $(SANITIZE_BUILD) && ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS) -L 'wavelets|spectral|fem|contact|solvers|scene'

reproduce: build
	@cmake --build $(BUILD) --target reproduce

bench: build
	@cmake --build $(BUILD) --target bench

clean:
	@rm -rf $(BUILD) $(BUILD).configure.log $(SANITIZE_BUILD) $(SANITIZE_BUILD).configure.log
