# The README's commands. Each one sets the machine up first: any missing
# Debian package is installed, then the project is configured and built in
# Release mode.
#
#   make run     build, then run the main job (the bundled scene, headless)
#   make test    build, then run the whole test suite through ctest
#   make bench   build, then run every benchmark and regenerate the tables
#                and plots of docs/performance.md (QUICK=1: a short smoke run
#                that writes into the build directory only)
#   make test-asan  the whole suite built with clang, AddressSanitizer and
#                UndefinedBehaviorSanitizer (build-san/), any report fails
#   make fuzz    build the libFuzzer targets in the same build (build-san/)
#                and run each for FUZZ_SECONDS (default 60); fails on a crash,
#                a sanitizer report, a leak or a timeout (tests/fuzz/README.md)

BUILD      ?= build
JOBS       ?= $(shell nproc 2>/dev/null || echo 2)
MAIN_SCENE ?= mods/doorbell
ALLOY      := $(BUILD)/apps/alloy
# One sanitizer build serves both test-asan and fuzz: every object is built
# once with clang, ASan, UBSan and libFuzzer's coverage hooks (which cost the
# suite little and, without libFuzzer linked, call the sanitizer runtime's
# no-op defaults). Two builds (g++ for the suite, clang for the fuzzers) took
# twice the CI time for the same findings.
SAN_BUILD  ?= build-san
FUZZ_SECONDS ?= 60

# Debian packages the build needs (the dependencies named in DESIGN.md, plus
# the well-kept libraries used for the command line and JSON, and the
# viewer's panels, PNG screenshots and font).
PACKAGES := build-essential cmake pkg-config \
            libluajit-5.1-dev libode-dev libeigen3-dev libsdl2-dev \
            libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev \
            libimgui-dev libpng-dev fonts-dejavu-core libxxhash-dev libzstd-dev libbox2d-dev \
            xvfb xdotool

# What `make test-asan` and `make fuzz` need besides: Debian's clang 16 (bookworm's default clang,
# 14, cannot build alloy: it lacks C++20's parenthesized aggregate
# initialization, which emplace_back relies on), libFuzzer and the sanitizers'
# runtimes for it (libclang-rt-16-dev, only recommended by clang), and
# llvm-symbolizer (llvm-16) for stacks with file and line.
FUZZ_CLANG    := 16
FUZZ_PACKAGES := clang-$(FUZZ_CLANG) libclang-rt-$(FUZZ_CLANG)-dev llvm-$(FUZZ_CLANG)

# The sanitizer build: -O1 (ASan's usual level: -O0 makes the suite several
# times slower, -O2 the build slower for no more findings), with asserts and
# frame pointers; the benchmarks are not built (they are not tests).
SANITIZER_FLAGS := -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
                   -DALLOY_BUILD_BENCH=OFF -DCMAKE_CXX_COMPILER=clang++-$(FUZZ_CLANG) -DALLOY_FUZZ=ON
# A sanitizer's report fails the test that triggered it (the build also has
# -fno-sanitize-recover=all); leaks are reported when each test exits.
SANITIZER_ENV := ASAN_OPTIONS=halt_on_error=1:abort_on_error=1:detect_leaks=1:check_initialization_order=1 \
                 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
                 ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-$(FUZZ_CLANG)/bin/llvm-symbolizer

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: run test bench deps deps-fuzz configure build configure-san test-asan fuzz clean

run: build
	$(ALLOY) run $(MAIN_SCENE)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

bench: build
	bench/run_all.sh $(BUILD) $(if $(QUICK),--quick)

configure-san: deps deps-fuzz
	cmake -S . -B $(SAN_BUILD) $(SANITIZER_FLAGS)

# The Xvfb mouse test (label xvfb) runs in `make test` only: it depends on a
# real X server's timing, which the sanitizers slow several times, and the
# viewer's code runs under them headless through its own tests anyway.
test-asan: configure-san
	cmake --build $(SAN_BUILD) -j $(JOBS)
	cd $(SAN_BUILD) && $(SANITIZER_ENV) ctest --output-on-failure -j $(JOBS) -LE xvfb

fuzz: configure-san
	cmake --build $(SAN_BUILD) -j $(JOBS) --target fuzz_all
	ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-$(FUZZ_CLANG)/bin/llvm-symbolizer \
	  tests/fuzz/run_fuzzers.sh $(SAN_BUILD) $(FUZZ_SECONDS)

# Installs only what is missing, so a machine that has everything runs no apt.
deps:
	@$(call install,$(PACKAGES))

deps-fuzz:
	@$(call install,$(FUZZ_PACKAGES))

define install
	missing=""; \
	for p in $(1); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "Installing missing Debian packages:$$missing"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi
endef

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j $(JOBS)

clean:
	rm -rf $(BUILD) $(SAN_BUILD)
