#!/usr/bin/env python3
"""bench/build_ab.py on real builds (fzk_haus at 1024^2, one pair each): the same binary and options
on both sides is the same build, and an option that changes the stores (no entry rule) is told
apart; every phase's figures and the paired ratios are reported for both sides.
Usage: build_ab_test.py PROJECT_SOURCE_DIR SHADOWTILES_CLI"""
import json
import os
import subprocess
import sys
import tempfile

source, cli = sys.argv[1], sys.argv[2]
script = os.path.join(source, "bench", "build_ab.py")
config = os.path.join(source, "config", "bench-standard.json")


def ab(tmp, *extra):
    out = os.path.join(tmp, "ab.json")
    run = subprocess.run([sys.executable, script, "--a", cli, "--config", config, "--scenes", "fzk_haus",
                          "--resolution", "1024", "--tile", "512", "--runs", "1", "--json", out, *extra],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    with open(out) as f:
        return run.stdout, json.load(f)["scenes"][0]


with tempfile.TemporaryDirectory() as tmp:
    text, same = ab(tmp)
    assert same["same_build"] is True, text
    assert "fzk_haus: stores the same build" in text and "store-diff:" not in text, text
    assert len(same["cpu_a_over_b"]) == 1
    a, b = same["runs"]["A"][0], same["runs"]["B"][0]
    assert abs(same["cpu_a_over_b"][0] - a["cpu_s"] / b["cpu_s"]) < 1e-9, same


    def row(text, label):  # a phase row's four cells: A, B, A / rays, B / rays
        line = next(l for l in text.splitlines() if l.startswith(f"| {label} |"))
        return [c.strip() for c in line.strip("|").split("|")[1:]]

    # The printed medians (one run each) are the runs' own figures.
    for phase in ("rays_thread_sum", "caps_thread_sum", "entry_rule_thread_sum", "encode_thread_sum"):
        cells = row(text, phase)
        for side, cell in zip(("A", "B"), cells[:2]):
            assert cell == f"{same['runs'][side][0]['stats']['seconds'][phase]:.3f}", (phase, cells)
    assert row(text, "rays_thread_sum")[2:] == ["1.000", "1.000"], text

    # Without the entry rule the tiles differ (store-diff says where), and B's entry rule is not timed.
    text, differ = ab(tmp, "--b-args=--entry-slack-texels 0")
    assert differ["same_build"] is False, text
    assert "fzk_haus: stores DIFFER" in text and "store-diff: different: tiles" in text, text
    assert differ["runs"]["B"][0]["stats"]["seconds"]["entry_rule_thread_sum"] == 0, differ["runs"]["B"][0]
    assert differ["runs"]["A"][0]["stats"]["seconds"]["entry_rule_thread_sum"] > 0
    assert row(text, "entry_rule_thread_sum")[1] == "0.000", text

    # A scene the config does not have is an error, not an empty report.
    bad = subprocess.run([sys.executable, script, "--a", cli, "--config", config, "--scenes", "nowhere"],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "no scene 'nowhere'" in bad.stderr, bad.stderr
print("build_ab: same build told from a different one")
