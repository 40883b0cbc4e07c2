# Convenience wrapper around CMake. `make` builds, `make test` sets up,
# builds and runs the tests, `make demo` runs the main job.
BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_FLAGS ?=

.PHONY: all setup configure build test test-sanitize test-tsan fuzz demo cluster-demo bench clean

all: build

setup:
	@bash scripts/setup.sh

# The packages come first even under `make -j`.
$(BUILD)/CMakeCache.txt: | setup
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

# ThreadSanitizer build of the threaded code's fast tests: the daemon's pool,
# the clients, and the core's tiles and smoothing on several threads.
test-tsan: setup
	cmake -S . -B $(BUILD)-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSC_SANITIZE=thread
	cmake --build $(BUILD)-tsan -j $(JOBS)
	cd $(BUILD)-tsan && ctest --output-on-failure -j $(JOBS) -LE slow -R '^(daemon|clients)_|^core_tiles_threads$$|^core_api$$|^core_noise_|^core_mesh_sample_dino_watertight$$|^core_mesh_sample_knot_watertight$$'

# The protocol decoder and the file readers under libFuzzer, ASan and UBSan
# (clang), for FUZZ_SECONDS each.
FUZZ_SECONDS ?= 60
fuzz: setup
	bash tests/proto/run-fuzz.sh $(BUILD)-fuzz $(FUZZ_SECONDS)

demo: build
	bash scripts/demo.sh $(BUILD)

# Three daemons on loopback TCP behind HAProxy, a verified load run through
# the front, everything stopped at the end.
cluster-demo: build
	bash scripts/cluster-demo.sh $(BUILD) 3

bench: build
	$(BUILD)/bin/shortcrust-bench
	$(BUILD)/bin/shortcrustd-bench

clean:
	rm -rf $(BUILD) $(BUILD)-asan $(BUILD)-tsan $(BUILD)-fuzz
