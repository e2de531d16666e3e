#!/usr/bin/env bash
# Installs the build tree into a scratch prefix, then configures, builds and runs the embedded
# self-test example (docs/examples/selftest_embed) against it, and checks its verdict.
# usage: embed_example_test.sh BUILD_DIR EXAMPLE_SOURCE_DIR
set -euo pipefail
BUILD="$1"
EXAMPLE="$2"
WORK="$BUILD/selftest-embed-test"
rm -rf "$WORK"
mkdir -p "$WORK"
cmake --install "$BUILD" --prefix "$WORK/prefix" > "$WORK/install.log"
# only Eigen, nlohmann_json and OpenSSL may be found: every other dependency of the package is hidden
HIDE=(-DCMAKE_DISABLE_FIND_PACKAGE_yaml-cpp=ON -DCMAKE_DISABLE_FIND_PACKAGE_urdfdom=ON
      -DCMAKE_DISABLE_FIND_PACKAGE_assimp=ON
      -DCMAKE_DISABLE_FIND_PACKAGE_Threads=ON -DCMAKE_DISABLE_FIND_PACKAGE_GTest=ON)
cmake -S "$EXAMPLE" -B "$WORK/build" -DCMAKE_PREFIX_PATH="$WORK/prefix" -DCMAKE_BUILD_TYPE=Release "${HIDE[@]}" \
  > "$WORK/configure.log" 2>&1 || { cat "$WORK/configure.log"; exit 1; }
# control: a consumer of the eval component cannot configure with those hidden (the check can fail)
mkdir -p "$WORK/eval-consumer"
cat > "$WORK/eval-consumer/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(eval_consumer LANGUAGES CXX)
find_package(ActionShift 0.1 REQUIRED COMPONENTS eval)
CMAKE
if cmake -S "$WORK/eval-consumer" -B "$WORK/eval-build" -DCMAKE_PREFIX_PATH="$WORK/prefix" "${HIDE[@]}" \
  > "$WORK/eval-configure.log" 2>&1; then
  echo "COMPONENTS eval configured without yaml-cpp/urdfdom/assimp: the dependency hiding does not work"
  exit 1
fi
grep -qE "yaml-cpp|PkgConfig|urdfdom|assimp|Threads" "$WORK/eval-configure.log" \
  || { echo "eval consumer failed for another reason:"; cat "$WORK/eval-configure.log"; exit 1; }
cmake --build "$WORK/build" > "$WORK/build.log" 2>&1 || { cat "$WORK/build.log"; exit 1; }
set +e
out=$("$WORK/build/selftest_embed")
rc=$?
set -e
echo "$out"
# the toy robot is wired with x/y swapped and roll negated: a MISMATCH naming exactly that
[ "$rc" = 1 ] || { echo "exit $rc, expected 1 (MISMATCH)"; exit 1; }
grep -qF "VERDICT: MISMATCH  (exit 1)" <<<"$out"
grep -qxF "  channels 0 and 1 SWAPPED; channel 3 sign FLIPPED" <<<"$out"
# its tool points down, so the frame is checked with the live rotation (only the gripper is not)
grep -qE "^  frame +base +confidence 1.00$" <<<"$out"
! grep -qF "  frame: " <<<"$out"
echo "selftest embed example: ok"
