"""CI (issue 45): `pedsynth report` in a real browser — headless Chromium (Debian's `chromium`), unmodified.

Usage: python3 tests/report_browser.py DATASET [--compare OTHER [--real-splits S]] --pedsynth PATH [--keep DIR]

OTHER is a second generated dataset or real annotations (`--real-splits` chooses their splits).

Writes the report of DATASET (beside OTHER), then with Chromium:
- loads it with console logging on: any console message fails (the page has no script, so a message can only
  be an error: a resource that failed to load, a malformed data URI);
- dumps the DOM it built: every plot's title is a heading of the page, with an inline SVG per plot;
- takes a screenshot: it must not be blank (many colours, a good share of non-white pixels).
--keep DIR copies the report and the screenshot there (docs/report.html, docs/report.png).
"""

import argparse
import html.parser
import pathlib
import shutil
import subprocess
import sys
import tempfile

from PIL import Image

TITLES_FROM = "src/dataset/report/mod.rs"


def fail(msg):
    print(f"report_browser: FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def titles():
    """The plots' titles as the source lists them (TITLES and SAMPLES_TITLE)."""
    text = pathlib.Path(TITLES_FROM).read_text()
    block = text[text.index("pub const TITLES"):text.index("];", text.index("pub const TITLES"))]
    out = [line.strip().strip(",").strip('"') for line in block.splitlines()[1:] if line.strip().startswith('"')]
    samples = text[text.index("pub const SAMPLES_TITLE"):].split('"')[1]
    return out + [samples]


class Headings(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.inside, self.headings, self.svgs = False, [], 0

    def handle_starttag(self, tag, attrs):
        if tag == "h2":
            self.inside = True
            self.headings.append("")
        if tag == "svg":
            self.svgs += 1

    def handle_endtag(self, tag):
        if tag == "h2":
            self.inside = False

    def handle_data(self, data):
        if self.inside:
            self.headings[-1] += data


def chromium():
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    fail("no chromium on PATH (Debian: apt-get install chromium)")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dataset")
    ap.add_argument("--compare")
    ap.add_argument("--real-splits")
    ap.add_argument("--pedsynth", required=True)
    ap.add_argument("--keep", type=pathlib.Path)
    args = ap.parse_args()
    browser = chromium()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        page = tmp / "report.html"
        cmd = [args.pedsynth, "report", args.dataset, "--out", str(page)]
        if args.compare:
            cmd += ["--compare", args.compare]
        if args.real_splits:
            cmd += ["--real-splits", args.real_splits]
        subprocess.run(cmd, check=True)
        url = page.resolve().as_uri()
        common = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                  f"--user-data-dir={tmp / 'profile'}", "--no-first-run", "--disable-extensions"]
        shot = tmp / "report.png"
        run = subprocess.run(common + ["--enable-logging=stderr", "--v=0", "--window-size=1560,2700",
                                       f"--screenshot={shot}", url], capture_output=True, text=True, timeout=180)
        console = [line for line in run.stderr.splitlines() if "CONSOLE" in line]
        if run.returncode != 0 or console:
            fail(f"chromium exited {run.returncode}; console: {console}\n{run.stderr[-3000:]}")
        dom = subprocess.run(common + ["--dump-dom", url], capture_output=True, text=True, timeout=180, check=True)
        parser = Headings()
        parser.feed(dom.stdout)
        want = titles()
        if parser.headings != want:
            fail(f"the page's headings {parser.headings} are not the plots' titles {want}")
        if parser.svgs != len(want) - 1:
            fail(f"{parser.svgs} SVG plots in the DOM, not {len(want) - 1}")
        if not shot.is_file():
            fail("no screenshot")
        img = Image.open(shot).convert("RGB")
        colours = img.getcolors(maxcolors=1 << 20) or []
        pixels = img.width * img.height
        white = sum(n for n, c in colours if min(c) >= 250)
        if len(colours) < 50 or white > 0.97 * pixels:
            fail(f"the screenshot looks blank: {len(colours)} colours, {white / pixels:.1%} white")
        print(f"report_browser: Chromium renders {page.name} ({page.stat().st_size // 1024} KB) with no console "
              f"message; {len(want)} titles and {parser.svgs} plots in its DOM; screenshot {img.width}x{img.height}, "
              f"{len(colours)} colours, {1 - white / pixels:.0%} not white")
        if args.keep:
            args.keep.mkdir(parents=True, exist_ok=True)
            shutil.copy(page, args.keep / "report.html")
            shutil.copy(shot, args.keep / "report.png")


if __name__ == "__main__":
    main()
