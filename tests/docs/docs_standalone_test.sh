#!/usr/bin/env bash
# The repository's documents stand on their own: no citation of design notes that are not in the
# repository ("DESIGN §…", "reference §…", "facts §…", "dependency notes", "DESIGN section …"), and
# every relative Markdown link in README.md and docs/ names a file that exists.
# usage: docs_standalone_test.sh SOURCE_DIR
set -u
src=${1:?usage: docs_standalone_test.sh SOURCE_DIR}
cd "$src" || exit 2
fail=0

pattern='DESIGN §|reference §|facts §|facts sheet|facts [0-9]|dependency notes|DESIGN sections?|DESIGN\.md|STYLE [0-9]|reference-implementation\.md|maniskill-and-panda-facts'
# this script names the patterns itself, so it is excluded
hits=$(grep -rnE "$pattern" README.md CMakeLists.txt cmake docs include src apps tests scripts configs 2>/dev/null |
  grep -v '^tests/docs/docs_standalone_test.sh:')
if [ -n "$hits" ]; then
  echo "FAILED: citations of documents that are not in the repository:" >&2
  echo "$hits" >&2
  fail=1
fi

# relative links [text](path) or [text](path#anchor) in Markdown files
while IFS= read -r md; do
  dir=$(dirname "$md")
  while IFS= read -r target; do
    case "$target" in http://* | https://* | mailto:* | '#'*) continue ;; esac
    path=${target%%#*}
    [ -z "$path" ] && continue
    if [ ! -e "$dir/$path" ]; then
      echo "FAILED: $md links to '$target', which does not exist" >&2
      fail=1
    fi
  done < <(grep -oE '\]\([^) ]+\)' "$md" | sed -E 's/^\]\((.*)\)$/\1/')
done < <(find README.md docs -name '*.md')

for doc in docs/semantics.md docs/reference.md; do
  [ -s "$doc" ] || { echo "FAILED: $doc is missing" >&2; fail=1; }
done

[ "$fail" = 0 ] && echo "docs stand on their own"
exit "$fail"
