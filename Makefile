# Convenience wrapper around CMake. `make` builds, `make test` sets up,
# builds and runs the tests, `make demo` runs the main job.
BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_FLAGS ?=

.PHONY: all setup configure build test test-sanitize demo bench clean

all: build

setup:
	@bash scripts/setup.sh

$(BUILD)/CMakeCache.txt:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)

configure: $(BUILD)/CMakeCache.txt

build: setup configure
	cmake --build $(BUILD) -j $(JOBS)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# ASan+UBSan build of the fast tests; the heavy reconstruction tests are
# labelled "slow" and run in the release build only.
test-sanitize: setup
	cmake -S . -B $(BUILD)-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSC_SANITIZE=address
	cmake --build $(BUILD)-asan -j $(JOBS)
	cd $(BUILD)-asan && ctest --output-on-failure -j $(JOBS) -LE slow

demo: build
	bash scripts/demo.sh $(BUILD)

bench: build
	$(BUILD)/bin/shortcrust-bench

clean:
	rm -rf $(BUILD) $(BUILD)-asan $(BUILD)-tsan
