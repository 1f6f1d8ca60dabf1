#!/usr/bin/env bash
# Every relative link of ROOT/README.md, ROOT/docs/*.md and ROOT/bench/RESULTS.md resolves: the file or folder it names
# exists, and a #fragment names a heading of the Markdown file it points to (GitHub's anchors:
# lower case, punctuation dropped, spaces as hyphens). Links inside fenced code and to other
# schemes (https:, mailto:) are not checked. Prints every broken link and fails if there is one.
#   bash tests/check_doc_links.sh ROOT
set -euo pipefail
root=${1:?usage: check_doc_links.sh ROOT}
files=("$root/README.md")
shopt -s nullglob
files+=("$root"/docs/*.md)
[[ -f $root/bench/RESULTS.md ]] && files+=("$root/bench/RESULTS.md")
[[ -f ${files[0]} ]] || { echo "check_doc_links: $root/README.md not found" >&2; exit 2; }

# The anchors a Markdown file defines, one per line (fenced code is not a heading).
anchors() {
  awk '/^ *```/ { fenced = !fenced; next }
       !fenced && /^#+ / {
         heading = $0; sub(/^#+ +/, "", heading); heading = tolower(heading)
         gsub(/[^a-z0-9 _-]/, "", heading); gsub(/ /, "-", heading); print heading
       }' "$1"
}

# Every link target of a Markdown file, one per line: [text](target) and ![alt](target).
links() {
  awk '/^ *```/ { fenced = !fenced; next }
       !fenced {
         line = $0
         while (match(line, /\]\([^) ]+\)/)) {
           print substr(line, RSTART + 2, RLENGTH - 3)
           line = substr(line, RSTART + RLENGTH)
         }
       }' "$1"
}

checked=0 broken=0
for file in "${files[@]}"; do
  folder=$(dirname "$file")
  while IFS= read -r target; do
    [[ $target =~ ^[a-zA-Z][a-zA-Z0-9+.-]*: ]] && continue  # https:, mailto:, ...
    checked=$((checked + 1))
    path=${target%%#*} fragment=
    [[ $target == *#* ]] && fragment=${target#*#}
    resolved=$file
    [[ -n $path ]] && resolved=$folder/$path
    if [[ ! -e $resolved ]]; then
      echo "$file: broken link ($target): $resolved does not exist"
      broken=$((broken + 1))
    elif [[ -n $fragment && $resolved == *.md ]] && ! anchors "$resolved" | grep -qxF -- "$fragment"; then
      echo "$file: broken link ($target): no heading #$fragment in $resolved"
      broken=$((broken + 1))
    fi
  done < <(links "$file")
done
echo "check_doc_links: ${#files[@]} files, $checked relative links, $broken broken"
[[ $broken -eq 0 ]]
