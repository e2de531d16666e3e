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
cmake -S "$EXAMPLE" -B "$WORK/build" -DCMAKE_PREFIX_PATH="$WORK/prefix" -DCMAKE_BUILD_TYPE=Release > "$WORK/configure.log" 2>&1 \
  || { cat "$WORK/configure.log"; exit 1; }
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
