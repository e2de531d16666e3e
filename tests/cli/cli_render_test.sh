#!/usr/bin/env bash
# End-to-end: actionshift render / montage / report. Usage: cli_render_test.sh <actionshift> <source dir>
set -euo pipefail
AS="$1"
SRC="$2"
source "$(dirname "$0")/lib.sh"

JOB=(--task pick_cube --split reference_seen --episodes 2)

# OSMesa (and llvmpipe's 100 MB libLLVM) is opened by the first render, never at start-up: linking it
# made every command start 3x slower (docs/results/benchmarks.md, "Command-line start-up")
if ldd "$AS" | grep -q 'libOSMesa\|libLLVM'; then bad "the CLI links OSMesa or LLVM at start-up"; else ok; fi
# without the library (hidden by a bind mount in a private mount namespace, where the machine allows
# one), a render is a one-line error naming the package, and writes nothing
MESA=$(ldconfig -p 2>/dev/null | awk '/libOSMesa\.so\.8 .*x86-64/ {print $NF; exit}')
if [ -n "$MESA" ] && unshare -m true 2>/dev/null; then
  run unshare -m sh -c "mount --bind /dev/null '$(readlink -f "$MESA")' && exec '$AS' render ${JOB[*]} --method no_adapt --out '$TMP/nomesa.png'"
  expect_rc 2 "render without OSMesa"; expect_one_line_error "render without OSMesa"
  expect_err "rendering needs OSMesa, which could not be loaded" "render without OSMesa"
  expect_err "apt-get install libosmesa6" "render without OSMesa names the package"
  [ ! -e "$TMP/nomesa.png" ] && ok || bad "a render without OSMesa left a file"
fi

# bad output paths and cameras: one line, exit 2, before any episode runs
run "$AS" render "${JOB[@]}" --method no_adapt --out "$TMP/x.txt"
expect_rc 2 "render to .txt"; expect_one_line_error "render to .txt"; expect_err "must end in .gif or .png" "render to .txt"
touch "$TMP/plainfile"
run "$AS" render "${JOB[@]}" --method no_adapt --out "$TMP/plainfile/x.gif"
expect_rc 2 "render under a file"; expect_one_line_error "render under a file"; expect_err "$TMP/plainfile/x.gif: --out:" "render under a file"
run "$AS" render "${JOB[@]}" --method no_adapt --out "$TMP"
expect_rc 2 "render to a directory"; expect_one_line_error "render to a directory"
run "$AS" render "${JOB[@]}" --method no_adapt --camera fisheye --out "$TMP/x.gif"
expect_rc 2 "unknown camera"; expect_one_line_error "unknown camera"; expect_err "--camera: 'fisheye'" "unknown camera"
[ ! -e "$TMP/x.gif" ] && ok || bad "a failed render left a file"
run "$AS" render "${JOB[@]}" --method no_adapt --contract 2 --out "$TMP/x.gif"
expect_rc 2 "contract outside the split"; expect_one_line_error "contract outside the split"
run "$AS" render "${JOB[@]}" --method no_adapt --size 10x10 --out "$TMP/x.gif"
expect_rc 2 "bad size"; expect_one_line_error "bad size"

# the render's outcome is the runner's record of the same episode
run "$AS" run "${JOB[@]}" --method oracle --threads 2 --progress off --out "$TMP/runs"
expect_rc 0 "run oracle"
run "$AS" render "${JOB[@]}" --method oracle --contract 1 --episode 0 --size 96x72 --out "$TMP/ep.gif"
expect_rc 0 "render gif"
printf '%s\n' "$OUT" > "$TMP/render.json"
python3 - "$TMP/render.json" "$TMP/runs" <<'PY' && ok || bad "render record differs from the runner's"
import glob, json, sys
r = json.loads(open(sys.argv[1]).read())
r.pop("rendered"); r.pop("clean")
recs = [json.loads(l) for f in glob.glob(sys.argv[2] + "/*.jsonl") for l in open(f)]
# --contract 1 --episode 0: contract 1's episode of block 0 (the block's order is seeded, not 0, 1)
assert r["contract_index"] == 1 and r["episode_index"] in (0, 1), r
match = [x for x in recs if x["episode_index"] == r["episode_index"]]
assert len(match) == 1 and match[0] == r, (match, r)
PY
# --contract I --episode E is contract I's episode of block E, whose order is seeded: in block 1 of this
# job contract 1 runs first (job episode 2), so E * contracts + I (episode 3, contract 0) was wrong
run "$AS" run --task pick_cube --split reference_seen --episodes 4 --method oracle --threads 2 --progress off --out "$TMP/runs4"
expect_rc 0 "run oracle, 4 episodes"
run "$AS" render --task pick_cube --split reference_seen --episodes 4 --method oracle --contract 1 --episode 1 --size 64x48 \
  --frame 0 --out "$TMP/ep4.png"
expect_rc 0 "render contract 1, episode 1"
printf '%s\n' "$OUT" > "$TMP/render4.json"
python3 - "$TMP/render4.json" "$TMP/runs4" <<'PY' && ok || bad "render --contract 1 --episode 1 is not contract 1's episode of block 1"
import glob, json, sys
r = json.loads(open(sys.argv[1]).read())
r.pop("rendered"); r.pop("clean")
assert r["contract_index"] == 1 and r["episode_index"] in (2, 3), r
recs = [json.loads(l) for f in glob.glob(sys.argv[2] + "/*.jsonl") for l in open(f)]
assert [x for x in recs if x["episode_index"] == r["episode_index"]] == [r]
PY
[ "$(head -c 6 "$TMP/ep.gif")" = "GIF89a" ] && ok || bad "not a GIF"
[ "$(stat -c %s "$TMP/ep.gif")" -gt 1000 ] && ok || bad "GIF too small"
run "$AS" render "${JOB[@]}" --method oracle --frame 0 --camera top --no-overlay --size 64x48 --out "$TMP/ep.png"
expect_rc 0 "render png"
[ "$(head -c 4 "$TMP/ep.png" | tail -c 3)" = "PNG" ] && ok || bad "not a PNG"
# --no-overlay, --clean and --label reach the renderer's settings (bound straight into them)
run "$AS" render "${JOB[@]}" --method oracle --frame 0 --camera top --size 64x48 --out "$TMP/ov.png"
expect_rc 0 "render png with the overlay"
cmp -s "$TMP/ep.png" "$TMP/ov.png" && bad "--no-overlay drew the same image as the overlay" || ok
printf '%s\n' "$OUT" > "$TMP/overlay.json"
run "$AS" render "${JOB[@]}" --method no_adapt --clean --label reference --frame 0 --camera top --size 64x48 --out "$TMP/clean.png"
expect_rc 0 "render --clean"
printf '%s\n' "$OUT" > "$TMP/clean.json"
python3 - "$TMP/overlay.json" "$TMP/clean.json" <<'PY' && ok || bad "--clean did not run the identity contract, or a render without it says clean"
import json, sys
plain, clean = (json.loads(open(f).read()) for f in sys.argv[1:3])
assert plain["clean"] is False and clean["clean"] is True, (plain["clean"], clean["clean"])
# the identity contract's sha256 (tests/install: the consumer prints it)
assert clean["contract_sha256"] == "6b38e10f94c37daf6ec3027f9fade885c611bbf710b732cc6f61ed134efb1eaa", clean
assert plain["contract_sha256"] != clean["contract_sha256"]
PY

# every job option of run reaches render: an external policy with --policy-files renders its run's job
cp "$SRC/docs/examples/external_policy.py" "$TMP/policy.py"
EXT=(--task pick_cube --split reference_seen --method oracle --episodes 2 --backbone "external:python3 $TMP/policy.py"
     --policy-files "$TMP/policy.py")
run "$AS" run "${EXT[@]}" --threads 1 --progress off --out "$TMP/ext"
expect_rc 0 "run an external policy"
run "$AS" render "${EXT[@]}" --size 48x36 --out "$TMP/ext.png"
expect_rc 0 "render an external policy with --policy-files"
ext_id=$(basename "$(ls "$TMP"/ext/*.jsonl)" .jsonl)
grep -qF "\"job_id\":\"$ext_id\"" <<<"$OUT" && ok || bad "render with --policy-files is not the run's job $ext_id"

# montage
run "$AS" montage "$TMP/ep.gif" "$TMP/ep.gif" --out "$TMP/two.gif"
expect_rc 0 "montage"; expect_out "2 panels" "montage"
run "$AS" montage "$TMP/missing.gif" --out "$TMP/two.gif"
expect_rc 2 "montage of a missing file"; expect_one_line_error "montage of a missing file"

# report after a premise-like run (tiny episode counts)
P=(--task pick_cube --split seen --episodes 4 --threads 2 --progress off --out "$TMP/premise")
run "$AS" run "${P[@]}" --method oracle; expect_rc 0 "premise oracle"
run "$AS" run "${P[@]}" --method no_adapt; expect_rc 0 "premise no_adapt"
run "$AS" gate1 --results "$TMP/premise"
run "$AS" report "$TMP/premise" --out "$TMP/report"
expect_rc 0 "report"; expect_out "(1 figure, " "report (one figure: Gate 1)"
[ -s "$TMP/report/index.html" ] && [ -s "$TMP/report/report.md" ] && ok || bad "report pages missing"
[ -s "$TMP/report/figures/gate1.svg" ] && ok || bad "no Gate 1 figure"
grep -q 'src="figures/gate1.svg"' "$TMP/report/index.html" && ok || bad "page lacks the Gate 1 figure"
missing=0; n=0
while read -r t; do
  n=$((n + 1))
  case "$t" in
    \#*) grep -q "id=\"${t#\#}\"" "$TMP/report/index.html" || { missing=1; echo "broken anchor $t" >&2; } ;;
    *) [ -e "$TMP/report/$t" ] || { missing=1; echo "broken link $t" >&2; } ;;
  esac
done < <(grep -o -E '(src|href)="[^"]+"' "$TMP/report/index.html" | sed -E 's/^(src|href)="//; s/"$//')
[ "$missing" = 0 ] && [ "$n" -ge 4 ] && ok || bad "report links ($n checked)"
run "$AS" report "$TMP/nowhere" --out "$TMP/report2"
expect_rc 2 "report of a missing directory"; expect_one_line_error "report of a missing directory"

# the page in a real headless browser, when Debian's chromium is installed (scripts/setup installs it):
# a copy of the page with a checker script appended loads every image and every local link and
# writes its verdict into the DOM, which chromium dumps after the load event
browser_check() {  # browser_check PAGE -> sets $verdict
  python3 - "$1" "$1.check.html" <<'PY'
import sys
page = open(sys.argv[1]).read()
checker = """<script>
window.addEventListener('load', () => {
  const bad = [];
  for (const i of document.images)
    if (!(i.complete && i.naturalWidth > 0)) bad.push('image:' + i.getAttribute('src'));
  for (const a of document.querySelectorAll('a[href]')) {
    const h = a.getAttribute('href');
    if (h.startsWith('#')) { if (!document.getElementById(h.slice(1))) bad.push('anchor:' + h); continue; }
    if (/^[a-z]+:/i.test(h)) continue;
    try { const x = new XMLHttpRequest(); x.open('GET', h, false); x.send(); }
    catch (e) { bad.push('link:' + h); }
  }
  document.body.setAttribute('data-check',
      bad.length ? 'BROKEN ' + bad.join(' ') : 'OK images=' + document.images.length);
});
</script>"""
assert '</body>' in page, 'no </body> in ' + sys.argv[1]
open(sys.argv[2], 'w').write(page.replace('</body>', checker + '</body>'))
PY
  run timeout 120 /usr/bin/chromium --headless --no-sandbox --disable-gpu --allow-file-access-from-files \
    --virtual-time-budget=10000 --dump-dom "file://$1.check.html"
  verdict=$(printf '%s' "$OUT" | grep -o 'data-check="[^"]*"' || true)
  rm -f "$1.check.html"
}
if [ -x /usr/bin/chromium ]; then
  browser_check "$TMP/report/index.html"
  case "$verdict" in
    'data-check="OK images='*) [ "${verdict//[!0-9]/}" -ge 1 ] && ok || bad "chromium saw no image: $verdict" ;;
    *) bad "chromium: the report page is broken: ${verdict:-no verdict (the page did not load)}" ;;
  esac
  # the check can fail: a page whose figure is missing is caught
  sed 's#figures/gate1.svg#figures/absent.svg#g' "$TMP/report/index.html" > "$TMP/report/broken.html"
  browser_check "$TMP/report/broken.html"
  case "$verdict" in *"image:figures/absent.svg"*"link:figures/absent.svg"*) ok ;; *) bad "chromium check missed a missing image and link: $verdict" ;; esac
  rm -f "$TMP/report/broken.html"
else
  echo "note: /usr/bin/chromium absent: the headless-browser check is skipped (scripts/setup installs chromium)"
fi
finish
