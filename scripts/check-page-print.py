#!/usr/bin/env python3
"""Checks that every value of every table of the report pages is readable on screen at
1280 px wide and on paper, in a Chromium print to A4 PDF.

    scripts/check-page-print.py HTML_DIR [PDF_DIR]

For each HTML_DIR/*.html (the pages scripts/report-pages.sh writes):

- on paper: the page is printed to PDF by headless Chromium (the page's own @page rule
  asks for A4); every page of the PDF must be A4, every word of its text layer (read with
  poppler's `pdftotext -bbox`) must lie within the page, and every word of every table
  cell and of every chart's text (title, axis labels, ticks, legend) must be among the
  PDF's words (a value or a chart pushed off the paper is not printed at all, so it is
  missing there);
- on screen: a copy of the page with a measuring script is laid out by headless Chromium
  in a 1280 px wide window; no table cell may reach past the window's right edge and the
  page may not scroll sideways.

Before the pages, the check is run on a page made to fail (a table too wide for both), and
must find it failing: a check that cannot fail checks nothing. Exit 0 when every page
passes, 1 when one fails (each problem on its own line), 2 when a tool is missing.

Needs Debian's chromium and poppler-utils.
"""

import collections
import html.parser
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

A4_POINTS = (595.3, 841.9)
SCREEN_WIDTH = 1280
# Positions in the PDF are in points; a word may touch the edge by rounding.
EDGE_POINTS = 0.5
CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


class TableCells(html.parser.HTMLParser):
    """The text of every table cell (th, td) of an HTML page and of every text of its
    charts (the SVG's text elements: titles, axis labels, ticks, legends)."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.cells = []
        self._cell = None
        self._svg = 0

    def handle_starttag(self, tag, attrs):
        if tag == "svg":
            self._svg += 1
        elif (tag in ("td", "th") and not self._svg) or (tag == "text" and self._svg):
            self._cell = []
        elif tag == "br" and self._cell is not None:
            self._cell.append(" ")

    def handle_endtag(self, tag):
        if tag == "svg":
            self._svg -= 1
        elif tag in ("td", "th", "text") and self._cell is not None:
            self.cells.append("".join(self._cell))
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def table_words(page_html):
    parser = TableCells()
    parser.feed(page_html)
    return collections.Counter(word for cell in parser.cells for word in cell.split())


def chromium(args, profile):
    return subprocess.run(
        ["chromium", *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args],
        capture_output=True,
        text=True,
        timeout=180,
    )


WORD = re.compile(
    r'<word xMin="([-\d.]+)" yMin="([-\d.]+)" xMax="([-\d.]+)" yMax="([-\d.]+)">(.*?)</word>'
)
PAGE = re.compile(r'<page width="([\d.]+)" height="([\d.]+)">')


def unescape(text):
    return html.unescape(text)


def paper_problems(page, pdf, profile):
    """What the A4 print of `page` loses."""
    result = chromium(
        ["--no-pdf-header-footer", f"--print-to-pdf={pdf}", page.as_uri()], profile
    )
    if result.returncode != 0 or not pdf.exists():
        return [f"{page.name}: chromium could not print it: {result.stderr.strip()[-300:]}"]
    layer = subprocess.run(
        ["pdftotext", "-bbox", str(pdf), "-"], capture_output=True, text=True, check=True
    ).stdout
    problems = []
    printed = collections.Counter()
    for number, chunk in enumerate(re.split(r"(?=<page )", layer)):
        size = PAGE.search(chunk)
        if not size:
            continue
        width, height = float(size.group(1)), float(size.group(2))
        if abs(width - A4_POINTS[0]) > 1 or abs(height - A4_POINTS[1]) > 1:
            problems.append(f"{page.name}: PDF page {number} is {width} x {height} pt, not A4")
        for x0, y0, x1, y1, word in WORD.findall(chunk):
            word = unescape(word)
            printed[word] += 1
            x0, y0, x1, y1 = map(float, (x0, y0, x1, y1))
            if x0 < -EDGE_POINTS or x1 > width + EDGE_POINTS or y1 > height + EDGE_POINTS:
                problems.append(
                    f"{page.name}: PDF page {number}: {word!r} at x {x0:.0f}..{x1:.0f} pt lies off the {width:.0f} pt page"
                )
    expected = table_words(page.read_text(encoding="utf-8"))
    # A word broken across lines (at a hyphen or a slash) is printed as two words: it is
    # there when the printed words, run together in reading order, hold it.
    run_together = "".join(unescape(w[-1]) for w in WORD.findall(layer))
    missing = collections.Counter(
        {w: n for w, n in (expected - printed).items() if w not in run_together}
    )
    if missing:
        shown = ", ".join(f"{w!r}" + (f" x{n}" if n > 1 else "") for w, n in missing.most_common(12))
        problems.append(
            f"{page.name}: {sum(missing.values())} words of its tables and charts are not on the printed A4 pages: {shown}"
        )
    return problems


MEASURE = """
<script>
window.addEventListener('load', () => {
  const width = window.innerWidth;
  const out = [];
  for (const cell of document.querySelectorAll('td, th')) {
    const box = cell.getBoundingClientRect();
    if (box.right > width + 0.5) out.push(cell.textContent.trim().slice(0, 40) + ' reaches ' + Math.round(box.right) + ' px');
  }
  const scroll = document.scrollingElement.scrollWidth;
  if (scroll > width) out.push('the page scrolls sideways: ' + scroll + ' px wide');
  const result = document.createElement('pre');
  result.id = 'measured';
  result.textContent = JSON.stringify({ width: width, problems: out });
  document.body.appendChild(result);
});
</script>
"""


def screen_problems(page, scratch, profile):
    """What a 1280 px wide window cannot show of `page`'s tables without scrolling."""
    copy = scratch / page.name
    copy.write_text(
        page.read_text(encoding="utf-8").replace("</body>", MEASURE + "</body>"), encoding="utf-8"
    )
    result = chromium(
        [f"--window-size={SCREEN_WIDTH},900", "--virtual-time-budget=5000", "--dump-dom", copy.as_uri()],
        profile,
    )
    found = re.search(r'<pre id="measured">(.*?)</pre>', result.stdout, re.S)
    if not found:
        return [f"{page.name}: chromium did not lay it out: {result.stderr.strip()[-300:]}"]
    measured = json.loads(html.unescape(found.group(1)))
    if measured["width"] != SCREEN_WIDTH:
        return [f"{page.name}: the window was {measured['width']} px wide, not {SCREEN_WIDTH}"]
    return [f"{page.name} at {SCREEN_WIDTH} px: {p}" for p in measured["problems"]]


def problems_of(page, pdf_dir, scratch, profile):
    return paper_problems(page, pdf_dir / (page.stem + ".pdf"), profile) + screen_problems(
        page, scratch, profile
    )


def failing_page(directory):
    """A page whose table is far too wide for the paper and the window."""
    cells = "".join(f"<td>value{i}&nbsp;{'x' * 30}</td>" for i in range(12))
    page = directory / "too-wide.html"
    page.write_text(
        "<!DOCTYPE html><html><head><meta charset='utf-8'><style>@page { size: A4; } "
        "td { white-space: nowrap; }</style></head><body><table><tr>"
        + cells
        + "</tr></table></body></html>",
        encoding="utf-8",
    )
    return page


def main():
    if len(sys.argv) not in (2, 3):
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    for tool in ("chromium", "pdftotext"):
        if not shutil.which(tool):
            print(f"error: {tool} not found (apt-get install chromium poppler-utils)", file=sys.stderr)
            return 2
    # Chromium takes the pages by file URI, which needs an absolute path.
    pages = sorted(pathlib.Path(sys.argv[1]).resolve().glob("*.html"))
    if not pages:
        print(f"error: no .html pages in {sys.argv[1]}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        pdf_dir = pathlib.Path(sys.argv[2]).resolve() if len(sys.argv) == 3 else tmp / "pdf"
        pdf_dir.mkdir(parents=True, exist_ok=True)
        scratch = tmp / "measure"
        scratch.mkdir()
        profile = tmp / "profile"
        bad = failing_page(tmp)
        bad_problems = problems_of(bad, tmp, scratch, profile)
        paper = any("not on the printed" in p or "off the" in p for p in bad_problems)
        screen = any(f"at {SCREEN_WIDTH} px" in p for p in bad_problems)
        if not (paper and screen):
            print("the check does not see a table too wide for the paper and the window:", file=sys.stderr)
            for problem in bad_problems or ["(no problem found)"]:
                print("  " + problem, file=sys.stderr)
            return 1
        failed = 0
        for page in pages:
            problems = problems_of(page, pdf_dir, scratch, profile)
            failed += bool(problems)
            for problem in problems:
                print(problem)
            if not problems:
                print(f"{page.name}: every table value on the A4 print and within {SCREEN_WIDTH} px")
        print(f"{len(pages) - failed} of {len(pages)} pages pass")
        return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
