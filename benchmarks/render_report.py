"""Open an acid report in headless Chromium and check it as a reader would see it.

Usage: python benchmarks/render_report.py reports/paper/report.html [--screenshot out.png]

Needs Debian's ``chromium`` package (``apt-get install chromium``). The report is loaded in
an iframe of a small probe page (file:// access allowed for this one run); a script in the
probe checks, on the rendered page:

* every <img> finished loading with a non-zero size and is laid out with a non-zero box;
* no figure reports a hidden line (``data-hidden``, from acid's pixel audit of the figure);
* no contradictory verdicts: no claim row that "agrees" while a row it implies
  (``data-implies``) "disagrees";
* the verdict counts at the top match the claim rows below;

and writes its findings into the DOM, which Chromium dumps. Exit status 0 when all hold,
1 otherwise, 2 when Chromium or the report is missing.
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
  var ok = imgs.filter(function (i) {{
    var box = i.getBoundingClientRect();
    return i.complete && i.naturalWidth > 0 && box.width > 0 && box.height > 0; }});
  var figs = doc ? Array.from(doc.querySelectorAll('figure[data-hidden]')) : [];
  var hidden = figs.filter(function (f) {{ return f.dataset.hidden !== '0'; }}).length;
  var rows = doc ? Array.from(doc.querySelectorAll('tr[data-claim]')) : [];
  var verdict = {{}};
  rows.forEach(function (r) {{ verdict[r.dataset.claim] = r.dataset.verdict; }});
  var bad = [];
  rows.forEach(function (r) {{
    if (r.dataset.verdict !== 'agrees') return;
    (r.dataset.implies || '').split(' ').filter(Boolean).forEach(function (j) {{
      if (verdict[j] === 'disagrees') bad.push(r.dataset.claim + '->' + j); }}); }});
  var countsOk = true;
  (doc ? Array.from(doc.querySelectorAll('#counts [data-verdict]')) : []).forEach(function (c) {{
    var n = rows.filter(function (r) {{ return r.dataset.verdict === c.dataset.verdict; }});
    if (String(n.length) !== c.dataset.count) countsOk = false; }});
  document.getElementById('verdict').textContent =
    'IMAGES ' + ok.length + '/' + imgs.length + ' HIDDEN ' + hidden + '/' + figs.length +
    ' CLAIMS ' + rows.length + ' CONTRADICTIONS ' + bad.length + ' [' + bad.join(',') + ']' +
    ' COUNTS ' + (countsOk ? 'ok' : 'mismatch') + ' TITLE ' + (doc ? doc.title : '?');
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
    m = re.search(r"IMAGES (\d+)/(\d+) HIDDEN (\d+)/(\d+) CLAIMS (\d+) CONTRADICTIONS "
                  r"(\d+) \[(.*?)\] COUNTS (\w+) TITLE (.*?)</pre>", dom)
    if not m:
        print("could not read the verdict from Chromium's DOM dump", file=sys.stderr)
        return 1
    loaded, total, hidden, figs = int(m[1]), int(m[2]), int(m[3]), int(m[4])
    claims, bad, which, counts_ok, title = int(m[5]), int(m[6]), m[7], m[8] == "ok", m[9]
    print(f"{report.name}: '{title}': {loaded}/{total} images loaded; {hidden} of {figs} "
          f"figures with a hidden line; {claims} claim rows, {bad} contradictions"
          + (f" ({which})" if bad else "") + f"; verdict counts {m[8]}")
    ok = total > 0 and loaded == total and hidden == 0 and bad == 0 and counts_ok
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
