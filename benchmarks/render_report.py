"""Open an acid report in headless Chromium and check that every image loaded.

Usage: python benchmarks/render_report.py reports/paper/report.html [--screenshot out.png]

Needs Debian's ``chromium`` package (``apt-get install chromium``). The report is loaded in
an iframe of a small probe page (file:// access allowed for this one run); a script in the
probe counts the report's <img> elements that finished loading with a non-zero size and
writes the verdict into the DOM, which Chromium dumps. Exit status 0 when every image
loaded, 1 otherwise, 2 when Chromium is missing.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--allow-file-access-from-files", "--virtual-time-budget=10000"]

PROBE = """<!doctype html><html><body>
<iframe id=r src="{src}" style="width:1200px;height:900px"></iframe>
<pre id=verdict>pending</pre>
<script>
document.getElementById('r').addEventListener('load', function () {{
  var doc = this.contentDocument, imgs = doc ? Array.from(doc.images) : [];
  var ok = imgs.filter(function (i) {{ return i.complete && i.naturalWidth > 0; }});
  document.getElementById('verdict').textContent =
    'IMAGES ' + ok.length + '/' + imgs.length + ' TITLE ' + (doc ? doc.title : '?');
}});
</script></body></html>"""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("report", type=Path)
    ap.add_argument("--screenshot", type=Path, help="also save a PNG of the page")
    args = ap.parse_args()
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        print("chromium not found (apt-get install chromium)", file=sys.stderr)
        return 2
    report = args.report.resolve()
    if not report.is_file():
        print(f"{report}: report not found", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        probe = Path(tmp) / "probe.html"
        probe.write_text(PROBE.format(src=report.as_uri()))
        common = FLAGS + [f"--user-data-dir={tmp}/profile"]
        dom = subprocess.run([exe, *common, "--dump-dom", probe.as_uri()], capture_output=True,
                             text=True, timeout=120).stdout
        if args.screenshot:
            subprocess.run([exe, *common, f"--screenshot={args.screenshot.resolve()}",
                            "--window-size=1200,2400", report.as_uri()],
                           capture_output=True, timeout=120)
    m = re.search(r"IMAGES (\d+)/(\d+) TITLE (.*?)</pre>", dom)
    if not m:
        print("could not read the verdict from Chromium's DOM dump", file=sys.stderr)
        return 1
    loaded, total, title = int(m[1]), int(m[2]), m[3]
    print(f"{report.name}: '{title}': {loaded}/{total} images loaded")
    return 0 if total > 0 and loaded == total else 1


if __name__ == "__main__":
    sys.exit(main())
