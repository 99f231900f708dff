#!/usr/bin/env bash
# Writes the HTML report of every shipped scenario and photographs it in headless Chromium:
# a whole-page PNG per report and one PNG per figure, to look at what a reader sees.
#
#   scripts/report-screenshots.sh [OUT_DIR]      (default: target/report-screenshots)
#
# Needs Debian's chromium (apt-get install chromium) and Node.js with npm; installs
# playwright-core (the browser driver only, no browser download) into OUT_DIR/node.
# The pages are scripts/report-pages.sh's.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-target/report-screenshots}"
mkdir -p "$out/png"
out="$(cd "$out" && pwd)"
command -v chromium >/dev/null || { echo "error: chromium not found (apt-get install chromium)" >&2; exit 2; }
scripts/report-pages.sh "$out"
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
