#!/usr/bin/env bash
# The report pages on paper and on screen: writes the page of every shipped scenario with
# every kind of analysis (scripts/report-pages.sh), prints each to an A4 PDF in headless
# Chromium and lays it out in a 1280 px window, and fails when a value of a table is not
# on the paper or reaches past the window (scripts/check-page-print.py). Installs Debian's
# chromium and poppler-utils when missing.
#
#   scripts/page-print-check.sh [OUT_DIR]     (default: target/page-print; the PDFs are
#                                              kept in OUT_DIR/pdf to look at)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-target/page-print}"
if ! command -v chromium >/dev/null || ! command -v pdftotext >/dev/null; then
  echo "installing Debian's chromium and poppler-utils"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq >/dev/null
  apt-get install -y -qq --no-install-recommends chromium poppler-utils fonts-dejavu-core >/dev/null
fi
scripts/report-pages.sh "$out"
python3 scripts/check-page-print.py "$out/html" "$out/pdf"
