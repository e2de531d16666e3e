#!/usr/bin/env bash
# usage: install_consumer_test.sh BUILD_DIR CONSUMER_SOURCE_DIR
set -euo pipefail
BUILD="$1"
CONSUMER="$2"
WORK="$BUILD/install-test"
rm -rf "$WORK"
mkdir -p "$WORK"
cmake --install "$BUILD" --prefix "$WORK/prefix" > "$WORK/install.log"
cmake -S "$CONSUMER" -B "$WORK/build" -DCMAKE_PREFIX_PATH="$WORK/prefix" -DCMAKE_BUILD_TYPE=Release > "$WORK/configure.log" 2>&1 \
  || { cat "$WORK/configure.log"; exit 1; }
cmake --build "$WORK/build" > "$WORK/build.log" 2>&1 || { cat "$WORK/build.log"; exit 1; }
# all_headers (built above) included every installed header together; none of the internal/ ones is installed
echo "installed headers: $(find "$WORK/prefix/include/actionshift" -name '*.hpp' | wc -l), compiled together"
[ ! -e "$WORK/prefix/include/actionshift/core/workers.hpp" ] || { echo "an internal header was installed"; exit 1; }
out=$("$WORK/build/consumer")
echo "$out"
grep -q "identity 6b38e10f94c37daf6ec3027f9fade885c611bbf710b732cc6f61ed134efb1eaa" <<<"$out"
grep -q "reference9 pool b177b082925800655dee9e93c02142f26a703fd2bdf1d97be56a2cb0bf0eeea3" <<<"$out"
out=$("$WORK/build/render_consumer") || { echo "render consumer failed: $out"; exit 1; }
echo "$out"
# the installed program must not load OSMesa (and llvmpipe's libLLVM) before it renders
if ldd "$WORK/build/render_consumer" | grep -q libOSMesa; then echo "render consumer links libOSMesa"; exit 1; fi
# the user-method example of docs/methods.md, built against the installed library alone
EXAMPLE="$(cd "$CONSUMER/../../.." && pwd)/docs/examples/method_plugin"
cmake -S "$EXAMPLE" -B "$WORK/method" -DCMAKE_PREFIX_PATH="$WORK/prefix" -DCMAKE_BUILD_TYPE=Release > "$WORK/method-configure.log" 2>&1 \
  || { cat "$WORK/method-configure.log"; exit 1; }
cmake --build "$WORK/method" > "$WORK/method-build.log" 2>&1 || { cat "$WORK/method-build.log"; exit 1; }
out=$("$WORK/method/separation_example" "$WORK/method-results" 3) || { echo "method example failed: $out"; exit 1; }
echo "$out"
[ "$(wc -l < "$(awk '{print $2}' <<<"$out")")" = 3 ] || { echo "method example: expected 3 records"; exit 1; }
# find_package(ActionShift COMPONENTS <c>) alone, for every component of the installed graph
COMPONENTS_FILE="$WORK/prefix/lib/cmake/ActionShift/ActionShiftComponents.cmake"
[ -f "$COMPONENTS_FILE" ] || COMPONENTS_FILE=$(find "$WORK/prefix" -name ActionShiftComponents.cmake | head -1)
comps=$(sed -n 's/^set(ACTIONSHIFT_COMPONENTS \(.*\))$/\1/p' "$COMPONENTS_FILE")
[ -n "$comps" ] || { echo "no component list in $COMPONENTS_FILE"; exit 1; }
for c in $comps; do
  cmake -S "$CONSUMER/../component" -B "$WORK/component-$c" -DCOMPONENT="$c" -DCMAKE_PREFIX_PATH="$WORK/prefix" \
    -DCMAKE_BUILD_TYPE=Release > "$WORK/component-$c-configure.log" 2>&1 \
    || { echo "find_package(ActionShift COMPONENTS $c) failed:"; cat "$WORK/component-$c-configure.log"; exit 1; }
  cmake --build "$WORK/component-$c" > "$WORK/component-$c-build.log" 2>&1 \
    || { echo "component $c: build failed:"; cat "$WORK/component-$c-build.log"; exit 1; }
  "$WORK/component-$c/component" > /dev/null || { echo "component $c: the program failed"; exit 1; }
  echo "component $c: find_package, link and run ok"
done
echo "install consumer: ok"
