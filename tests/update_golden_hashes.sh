#!/bin/sh
# Regenerates tests/runtime/golden_hashes.txt, the state hashes of the bundled
# scenes that tests/runtime/scene_hash_test.cpp checks, after an intended
# change to the physics (a resolver, a scene, a mod). Run from the source
# tree: tests/update_golden_hashes.sh [BUILD_DIR]   (default: build)
# Then look at `git diff tests/runtime/golden_hashes.txt`: only the scenes
# the change should touch may move. Commit the file with the change.
set -eu
build=${1:-build}
cmake --build "$build" -j2 --target runtime_scene_tests
ALLOY_UPDATE_GOLDEN=1 "$build/tests/runtime/runtime_scene_tests" --gtest_filter='BundledScenes/GoldenHash.*'
"$build/tests/runtime/runtime_scene_tests" --gtest_filter='BundledScenes/GoldenHash.*'
