# The README's commands. Each one sets the machine up first: any missing
# Debian package is installed, then the project is configured and built in
# Release mode.
#
#   make run     build, then run the main job (the bundled scene, headless)
#   make test    build, then run the whole test suite through ctest
#   make bench   build, then run every benchmark and regenerate the tables
#                and plots of docs/performance.md (QUICK=1: a short smoke run
#                that writes into the build directory only)

BUILD      ?= build
JOBS       ?= $(shell nproc 2>/dev/null || echo 2)
MAIN_SCENE ?= mods/doorbell
ALLOY      := $(BUILD)/apps/alloy

# Debian packages the build needs (the dependencies named in DESIGN.md, plus
# the well-kept libraries used for the command line and JSON, and the
# viewer's panels, PNG screenshots and font).
PACKAGES := build-essential cmake pkg-config \
            libluajit-5.1-dev libode-dev libeigen3-dev libsdl2-dev \
            libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev \
            libimgui-dev libpng-dev fonts-dejavu-core

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: run test bench deps configure build clean

run: build
	$(ALLOY) run $(MAIN_SCENE)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

bench: build
	bench/run_all.sh $(BUILD) $(if $(QUICK),--quick)

# Installs only what is missing, so a machine that has everything runs no apt.
deps:
	@missing=""; \
	for p in $(PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "Installing missing Debian packages:$$missing"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j $(JOBS)

clean:
	rm -rf $(BUILD)
