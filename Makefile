# Thin front end to CMake. `make test` and `make reproduce` are the README's two commands.
BUILD ?= build
JOBS  ?= 2
OUT   ?= $(CURDIR)/out

.PHONY: deps configure build test reproduce bench clean

deps:
	@./scripts/install-deps

configure: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DWBM_OUT_DIR=$(OUT) > $(BUILD).configure.log 2>&1 \
	  || { cat $(BUILD).configure.log; exit 1; }

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

test: build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

reproduce: build
	@cmake --build $(BUILD) --target reproduce

bench: build
	@cmake --build $(BUILD) --target bench

clean:
	@rm -rf $(BUILD) $(BUILD).configure.log
