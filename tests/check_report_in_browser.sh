#!/usr/bin/env bash
# prism-suite --report in a real browser (Debian's headless Chromium): renders a few of the
# project's scenes with a report, then
#   1. loads a copy of the page with a checking script put first in its <head>: it records every
#      error event (a failed image included) and console error or warning, then, once the page
#      has loaded, checks that every image loaded, that every compared row shows its three
#      images, that sorting by PSNR and by time orders the rows, and that the topic filter
#      hides the other topics; it writes its findings into the page, which --dump-dom prints;
#   2. takes a screenshot of the page itself, unmodified, and fails on any console message;
#   3. loads the screenshot into a canvas and counts its colours: a blank page has one.
# Without Chromium it prints "skipped" (ctest's SKIP_REGULAR_EXPRESSION) and succeeds.
#   bash tests/check_report_in_browser.sh PRISM_SUITE SCENES_FOLDER WORK_FOLDER
set -euo pipefail
suite=$1 scenes=$2 work=$3

browser=
for candidate in chromium chromium-browser google-chrome; do
  if command -v "$candidate" >/dev/null; then browser=$(command -v "$candidate"); break; fi
done
if [[ -z $browser ]]; then
  echo "skipped: Chromium not found (bash tools/install-dependencies.sh --with-browser installs it)"
  exit 0
fi

rm -rf "$work"
mkdir -p "$work"
report=$work/report
fail() { echo "FAIL: $*" >&2; exit 1; }

# Two topics, so that the filter has something to hide; the tone-mapping scenes' EXR rows have no
# reference (a render alone), their PNG rows and the lights' have one. At half size with fewer
# samples the PSNRs differ from row to row, so sorting has work to do, and a threshold of 35 dB
# passes some rows and fails others.
status=0
"$suite" "$scenes" --topics lights,tonemapping --scale 0.5 --max-samples 4 --threshold 35 --threads 2 --report "$report" \
  > "$work/suite.txt" || status=$?
cat "$work/suite.txt"
[[ $status -le 1 ]] || fail "prism-suite exited with $status"
[[ -f $report/report.html ]] || fail "no $report/report.html"

# A fresh profile every time, and no traffic the machine's closed network would refuse.
chromium() {
  local profile
  profile=$(mktemp -d "$work/profile.XXXXXX")
  timeout 120 "$browser" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync \
    --user-data-dir="$profile" "$@"
}

# 1. The checking copy, beside the page so that its relative image paths resolve.
cat > "$work/check-script.html" <<'HTML'
<script>
window.__problems = [];
window.addEventListener('error', (event) => {
  const target = event.target && event.target !== window ? (event.target.src || event.target.href || event.target.tagName) : '';
  window.__problems.push('error: ' + (event.message || target));
}, true);
for (const level of ['error', 'warn']) {
  const original = console[level];
  console[level] = (...args) => { window.__problems.push(level + ': ' + args.join(' ')); original.apply(console, args); };
}
window.addEventListener('load', () => {
  const loaded = (image) => image.complete && image.naturalWidth > 0;
  const body = document.querySelector('#rows tbody');
  const rows = () => Array.from(body.rows);
  const all = rows();
  const images = Array.from(document.images);
  const compared = all.filter((row) => row.dataset.psnr !== '');
  const incomplete = compared.filter((row) => {
    const own = Array.from(row.querySelectorAll('img'));
    return own.length !== 3 || !own.every(loaded);
  });
  const ordered = (key, descending) => {
    const values = rows().map((row) => row.dataset[key]);
    const numbers = values.filter((v) => v !== '').map((v) => (v === 'inf' ? Infinity : Number(v)));
    const last = values.findIndex((v) => v === '');
    const blanksLast = last < 0 || values.slice(last).every((v) => v === '');
    return blanksLast && numbers.every((v, i) => i === 0 || (descending ? numbers[i - 1] >= v : numbers[i - 1] <= v));
  };
  const sorts = [];
  for (const key of ['psnr', 'seconds']) {
    const button = document.querySelector('button.sort[data-sort="' + key + '"]');
    if (!button) { sorts.push(key + ':missing'); continue; }
    button.click();
    const up = ordered(key, false);
    button.click();
    const down = ordered(key, true);
    sorts.push(key + ':' + (up && down ? 'ok' : 'wrong'));
  }
  const select = document.getElementById('topic');
  select.value = 'lights';
  select.dispatchEvent(new Event('change'));
  const shown = all.filter((row) => !row.hidden);
  const filtered = shown.length > 0 && shown.length < all.length && shown.every((row) => row.dataset.topic === 'lights');
  select.value = '';
  select.dispatchEvent(new Event('change'));
  const restored = all.every((row) => !row.hidden);
  const result = document.createElement('pre');
  result.id = 'browser-check';
  result.textContent = ['rows=' + all.length, 'compared=' + compared.length, 'images=' + images.length,
    'broken=' + images.filter((i) => !loaded(i)).length, 'incomplete=' + incomplete.length, 'sorts=' + sorts.join(','),
    'filter=' + (filtered && restored ? 'ok' : 'wrong'), 'problems=' + window.__problems.length,
    'details=' + window.__problems.join(' | ')].join(' ');
  document.body.appendChild(result);
});
</script>
HTML
awk -v script="$work/check-script.html" '{ print } /<head>/ && !done { while ((getline line < script) > 0) print line; done = 1 }' \
  "$report/report.html" > "$report/check.html"
chromium --virtual-time-budget=10000 --dump-dom "file://$(realpath "$report/check.html")" > "$work/dom.html" 2> "$work/dom.log" ||
  fail "Chromium could not load the page (see $work/dom.log)"
check=$(grep -o '<pre id="browser-check">[^<]*' "$work/dom.html" | sed 's/.*>//') || true
echo "in the browser: $check"
[[ -n $check ]] || fail "the checking script wrote nothing: the page did not load"
field() { sed -n "s/.*\\b$1=\\([^ ]*\\).*/\\1/p" <<< "$check"; }
rows=$(field rows) compared=$(field compared)
[[ $rows -ge 2 ]] || fail "the report has $rows rows"
[[ $compared -ge 1 ]] || fail "no row was compared with a reference"
[[ $(field broken) == 0 ]] || fail "$(field broken) images did not load"
[[ $(field incomplete) == 0 ]] || fail "$(field incomplete) compared rows lack a loaded render, reference or difference"
[[ $(field images) -ge $((3 * compared)) ]] || fail "$(field images) images for $compared compared rows"
[[ $(field sorts) == psnr:ok,seconds:ok ]] || fail "sorting: $(field sorts)"
[[ $(field filter) == ok ]] || fail "the topic filter did not hide the other topic"
[[ $(field problems) == 0 ]] || fail "errors in the page: ${check#*details=}"

# 2. The page as written: a screenshot, and no console message of any level.
chromium --enable-logging=stderr --v=0 --window-size=1280,1600 --hide-scrollbars \
  --screenshot="$work/screenshot.png" "file://$(realpath "$report/report.html")" > "$work/shot.log" 2>&1 ||
  fail "Chromium could not take the screenshot (see $work/shot.log)"
if grep -q ':CONSOLE' "$work/shot.log"; then
  grep ':CONSOLE' "$work/shot.log" >&2
  fail "the page wrote to the console"
fi
[[ -s $work/screenshot.png ]] || fail "no screenshot"

# 3. The screenshot's colours, counted in the browser (a canvas may read a file:// image only
# with --allow-file-access-from-files).
cat > "$work/colours.html" <<'HTML'
<!DOCTYPE html><html><body><script>
const image = new Image();
const say = (text) => { const out = document.createElement('pre'); out.id = 'colours'; out.textContent = text; document.body.appendChild(out); };
image.onload = () => {
  const canvas = document.createElement('canvas');
  canvas.width = image.naturalWidth;
  canvas.height = image.naturalHeight;
  const context = canvas.getContext('2d');
  context.drawImage(image, 0, 0);
  const data = context.getImageData(0, 0, canvas.width, canvas.height).data;
  const colours = new Set();
  for (let i = 0; i < data.length; i += 4) colours.add((data[i] << 16) | (data[i + 1] << 8) | data[i + 2]);
  say('colours=' + colours.size + ' size=' + canvas.width + 'x' + canvas.height);
};
image.onerror = () => say('colours=0 unreadable');
image.src = 'screenshot.png';
</script></body></html>
HTML
chromium --allow-file-access-from-files --virtual-time-budget=10000 --dump-dom "file://$(realpath "$work/colours.html")" \
  > "$work/colours.dom" 2> "$work/colours.log" || fail "Chromium could not read the screenshot"
colours=$(grep -o '<pre id="colours">[^<]*' "$work/colours.dom" | sed 's/.*>//') || true
echo "screenshot: $colours"
count=${colours#colours=}
count=${count%% *}
[[ -n $count && $count -ge 64 ]] || fail "the screenshot is blank or nearly so ($colours)"
echo "report checked in $("$browser" --version 2>/dev/null || echo Chromium): $rows rows, $compared compared"
