#!/usr/bin/env python3
"""bench/dagmh_incache.py on a real bench_dagmh run (the steps tile, point lookups in row order, MMH and
DAG-MH): the section it writes holds that cell with both rates and their ratio, replaces an older
section without touching the rest of the file, and judges the 1.3x target from the ratio.
Usage: dagmh_incache_test.py PROJECT_SOURCE_DIR BENCH_DAGMH"""
import os
import re
import subprocess
import sys
import tempfile

script = os.path.join(sys.argv[1], "bench", "dagmh_incache.py")
bench = sys.argv[2]

with tempfile.TemporaryDirectory() as tmp:
    md = os.path.join(tmp, "BENCH.md")
    open(md, "w").write("# Benchmarks\n\nkept above\n\n<!-- dagmh-incache:begin -->\nold section\n"
                        "<!-- dagmh-incache:end -->\n\nkept below\n")
    subprocess.run([sys.executable, script, "--bench", bench, "--md", md,
                    "--filter", "BM_Lookup/0/4096/[12]/1/0/min_time:0.200/threads:1$"], check=True)
    text = open(md).read()
    assert "kept above" in text and "kept below" in text, text
    assert "old section" not in text and text.count("<!-- dagmh-incache:begin -->") == 1, text
    rows = re.findall(r"^\| steps \| point \| coherent \| ([0-9.]+) \| ([0-9.]+) \| ([0-9.]+) \| (yes|no) \|$", text, re.M)
    assert len(rows) == 1, text
    mmh, dagmh, ratio, verdict = float(rows[0][0]), float(rows[0][1]), float(rows[0][2]), rows[0][3]
    assert mmh > 0 and dagmh > 0, rows
    assert abs(ratio - mmh / dagmh) <= 0.01 * ratio + 0.01, rows  # rates are rounded to 0.01 M/s
    assert verdict == ("yes" if ratio <= 1.3 else "no"), rows
    assert re.search(rf"- {1 if verdict == 'yes' else 0} of 1 cells within 1.3x; worst {rows[0][2]} "
                     r"\(steps point coherent\)", text), text
    # A run without both methods is an error, not an empty section.
    bad = subprocess.run([sys.executable, script, "--bench", bench, "--md", md,
                          "--filter", "BM_Lookup/0/4096/1/1/0/min_time:0.200/threads:1$"], capture_output=True, text=True)
    assert bad.returncode != 0 and "no MMH / DAG-MH" in bad.stderr, bad
print("ok")
