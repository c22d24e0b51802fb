#!/usr/bin/python3
"""Fails unless every consumer's "lit value" lines equal `shadowtiles query --json`'s answers for
the same points (lit exactly, value as the same float32), and the points are not all one answer.
    compare_answers.py CLI_JSON NAME=ANSWERS_FILE..."""
import json
import sys

import numpy as np

cli = json.load(open(sys.argv[1]))
cli_lit = np.array([row["lit"] for row in cli], dtype=bool)
cli_value = np.array([np.inf if row["value"] == "inf" else row["value"] for row in cli], dtype=np.float32)
shadowed = int((~cli_lit).sum())
if shadowed < len(cli) // 20 or shadowed > len(cli) - len(cli) // 20:
    sys.exit("degenerate points: %d of %d shadowed (want a real mix)" % (shadowed, len(cli)))
failed = False
for arg in sys.argv[2:]:
    name, path = arg.split("=", 1)
    rows = np.loadtxt(path, dtype=np.float64, ndmin=2)
    if rows.shape[0] != len(cli):
        print("%s: %d answers, the CLI gave %d" % (name, rows.shape[0], len(cli)))
        failed = True
        continue
    lit = rows[:, 0].astype(bool)
    value = rows[:, 1].astype(np.float32)
    bad = np.flatnonzero((lit != cli_lit) | (value != cli_value))
    if bad.size:
        i = bad[0]
        print("%s: %d of %d answers differ from the CLI's; first at point %d: %s %r vs %s %r"
              % (name, bad.size, len(cli), i, lit[i], value[i], cli_lit[i], cli_value[i]))
        failed = True
    else:
        print("%s: %d answers equal the CLI's (%d shadowed)" % (name, len(cli), shadowed))
sys.exit(1 if failed else 0)
