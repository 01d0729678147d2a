"""Worker processes do not run the command's main script again (``workers_skip_main``).

multiprocessing's ``spawn`` (how Dask starts a local cluster's workers) re-runs the parent's
main script in every new process; for ``acid``'s console script that is the whole
command-line interface, imported for nothing in each worker. The test spawns a real process
from a main script that leaves a line each time it runs.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

MAIN = """import sys, time
with open(sys.argv[1], "a") as f:   # one line each time this file runs
    f.write(__name__ + "\\n")
if __name__ == "__main__":
    import multiprocessing
    if sys.argv[2] == "skip":
        from acid.executor import workers_skip_main
        workers_skip_main()
    p = multiprocessing.get_context("spawn").Process(target=time.sleep, args=(0.0,))
    p.start()
    p.join()
    sys.exit(p.exitcode)
"""


@pytest.mark.parametrize("skip", [True, False])
def test_spawned_workers_do_not_run_the_main_script_again(tmp_path, skip):
    script, mark = tmp_path / "main_script.py", tmp_path / "runs.txt"
    script.write_text(MAIN)
    subprocess.run([sys.executable, str(script), str(mark), "skip" if skip else "keep"],
                   check=True, timeout=60)
    runs = mark.read_text().split()
    # without the call the child imports the script again as __mp_main__ (what the CLI did)
    assert runs == (["__main__"] if skip else ["__main__", "__mp_main__"])
