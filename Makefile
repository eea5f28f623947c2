# The README's commands. Everything builds out of tree under build/.
#   make demo       build (Release), evaluate the built-in demo scene, write
#                   build/demo-result.off
#   make test       gcc build with -Werror + the whole suite, then again under ASan+UBSan,
#                   and a clang -Werror compile check
#   make sanitize   only the ASan+UBSan build and suite
#   make bench      Release build and the benchmarks in bench/ (with the CGAL comparison
#                   when libcgal-dev is installed)
#   make fuzz       libFuzzer (clang) on every parser and the evaluator for FUZZ_SECONDS
#                   each (default 60)
#   make fuzz-csg   differential CSG fuzzing against the winding-number oracle for SECONDS
#                   (default 600); failures are saved under tests/data/csg-regressions/
#   make install    Release build installed under $(DESTDIR)$(PREFIX) (default /usr/local):
#                   bin, include, lib (static and shared), pkg-config, CMake package, man
#   make uninstall  removes the files that make install listed there

JOBS ?= 2
MAKEFLAGS += --no-print-directory
FUZZ_SECONDS ?= 60
SECONDS ?= 600
BUILD := build
PREFIX ?= /usr/local
CMAKE_FLAGS := -DMCSG_WERROR=ON

.PHONY: all demo test check sanitize clang-check bench fuzz fuzz-csg deps clean install \
        uninstall

all: demo

deps:
	@bash tools/ensure-deps.sh

$(BUILD)/release/meshcsg: deps FORCE
	@cmake -S . -B $(BUILD)/release -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(BUILD)/release -j $(JOBS) --target meshcsg_cli

demo: $(BUILD)/release/meshcsg
	./$(BUILD)/release/meshcsg demo -o $(BUILD)/demo-result.off

test: check sanitize clang-check

check: deps
	CC=gcc cmake -S . -B $(BUILD)/test -DCMAKE_BUILD_TYPE=RelWithDebInfo $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD)/test -j $(JOBS)
	cd $(BUILD)/test && ctest --output-on-failure -j $(JOBS)

sanitize: deps
	CC=gcc cmake -S . -B $(BUILD)/asan -DCMAKE_BUILD_TYPE=Debug -DMCSG_SANITIZE=ON -DMCSG_SHARED=OFF $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD)/asan -j $(JOBS)
	cd $(BUILD)/asan && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --output-on-failure -j $(JOBS)

# Builds everything with clang and -Werror (no test run): the code must stay portable C11.
clang-check:
	@bash tools/ensure-deps.sh clang
	CC=clang cmake -S . -B $(BUILD)/clang -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD)/clang -j $(JOBS)

bench: deps
	@cmake -S . -B $(BUILD)/release -DCMAKE_BUILD_TYPE=Release -DMCSG_CGAL_BENCH=ON $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD)/release -j $(JOBS)
	bash bench/run.sh $(BUILD)/release

fuzz:
	@bash tools/ensure-deps.sh clang
	CC=clang cmake -S . -B $(BUILD)/fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMCSG_FUZZ=ON $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD)/fuzz -j $(JOBS)
	bash fuzz/run.sh $(BUILD)/fuzz $(FUZZ_SECONDS)

fuzz-csg: deps
	CC=gcc cmake -S . -B $(BUILD)/test -DCMAKE_BUILD_TYPE=RelWithDebInfo $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD)/test -j $(JOBS) --target fuzz_csg
	MCSG_TEST_DATA="$$(pwd)/tests/data" ./$(BUILD)/test/tests/fuzz_csg $(SECONDS)

install: deps
	@cmake -S . -B $(BUILD)/release -DCMAKE_BUILD_TYPE=Release -DMCSG_SHARED=ON \
	  -DCMAKE_INSTALL_PREFIX="$(PREFIX)" $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD)/release -j $(JOBS) --target meshcsg_cli meshcsg meshcsg_shared
	DESTDIR="$(DESTDIR)" cmake --install $(BUILD)/release

uninstall:
	bash tools/uninstall.sh "$(DESTDIR)$(PREFIX)"

clean:
	rm -rf $(BUILD)

FORCE:
