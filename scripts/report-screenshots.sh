#!/usr/bin/env bash
# Writes the HTML report of every shipped scenario and photographs it in headless Chromium:
# a whole-page PNG per report and one PNG per figure, to look at what a reader sees.
#
#   scripts/report-screenshots.sh [OUT_DIR]      (default: target/report-screenshots)
#
# Needs Debian's chromium (apt-get install chromium) and Node.js with npm; installs
# playwright-core (the browser driver only, no browser download) into OUT_DIR/node.
# Sample counts are kept small so that the whole script runs in a few minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-target/report-screenshots}"
mkdir -p "$out/html" "$out/png"
out="$(cd "$out" && pwd)"
command -v chromium >/dev/null || { echo "error: chromium not found (apt-get install chromium)" >&2; exit 2; }
cargo build --release -p rvtol --quiet
rvtol=target/release/rvtol
for scenario in scenarios/*.json; do
  name="$(basename "$scenario" .json)"
  json="$out/html/$name.run.json"
  case "$name" in
    rv40e-transmission*) samples=2000 ;;
    *torsion*|rv40e-elastic|rv80e-contact) samples=20000 ;;
    *) samples=100000 ;;
  esac
  "$rvtol" run "$scenario" --samples "$samples" --json "$json" --quiet > "$out/html/$name.run.txt" || true
  reports=("$json")
  case "$name" in
    rv20e-hysteresis|ishigami|sobol-g|linear-stack-correlated|allocation-linear)
      "$rvtol" sensitivity "$scenario" --samples 4096 --bootstrap 200 --json "$out/html/$name.sensitivity.json" --quiet > /dev/null
      reports+=("$out/html/$name.sensitivity.json") ;;
    shapley-linear-gaussian)
      "$rvtol" sensitivity "$scenario" --samples 4096 --bootstrap 200 --shapley --json "$out/html/$name.sensitivity.json" --quiet > /dev/null
      reports+=("$out/html/$name.sensitivity.json") ;;
  esac
  case "$name" in
    allocation-linear)
      "$rvtol" allocate "$scenario" --output gap_mm --target "sd <= 0.02" --json "$out/html/$name.allocation.json" --quiet > /dev/null || true
      reports+=("$out/html/$name.allocation.json") ;;
    rv20e-selective-fitting)
      "$rvtol" allocate "$scenario" --output hysteresis_arcmin --target "p99.865 <= 1.0" --json "$out/html/$name.allocation.json" --quiet > /dev/null || true
      reports+=("$out/html/$name.allocation.json") ;;
  esac
  "$rvtol" report "${reports[@]}" --scenario "$scenario" -o "$out/html/$name.html" > /dev/null
done
node_dir="$out/node"
if [ ! -d "$node_dir/node_modules/playwright-core" ]; then
  mkdir -p "$node_dir"
  (cd "$node_dir" && npm install --silent --no-audit --no-fund playwright-core@1 > /dev/null)
fi
cat > "$node_dir/shoot.js" <<'JS'
const { chromium } = require('playwright-core');
const fs = require('fs');
const path = require('path');
(async () => {
  const [htmlDir, pngDir] = process.argv.slice(2);
  const browser = await chromium.launch({
    executablePath: '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  // The page must not reach out: every request other than the file itself is refused.
  const requests = [];
  page.on('request', (r) => { if (!r.url().startsWith('file:')) requests.push(r.url()); });
  for (const file of fs.readdirSync(htmlDir).filter((f) => f.endsWith('.html')).sort()) {
    const stem = path.basename(file, '.html');
    await page.goto('file://' + path.join(htmlDir, file));
    await page.screenshot({ path: path.join(pngDir, `${stem}.png`), fullPage: true });
    const figures = await page.$$('figure');
    for (let i = 0; i < figures.length; i++) {
      await figures[i].screenshot({ path: path.join(pngDir, `${stem}.figure-${String(i + 1).padStart(2, '0')}.png`) });
    }
    console.log(`${file}: ${figures.length} figures`);
  }
  await browser.close();
  if (requests.length) { console.error('network requests: ' + requests.join(', ')); process.exit(1); }
})();
JS
node "$node_dir/shoot.js" "$out/html" "$out/png"
echo "screenshots in $out/png"
