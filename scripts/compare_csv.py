#!/usr/bin/env python3
"""Compares the CSV files of two result folders column by column, ignoring wall times.

  compare_csv.py OLD_DIR NEW_DIR              every *.csv under OLD_DIR against NEW_DIR
  compare_csv.py --run RUN_CSV STUDY_CSV       the rows of `stiffbench run` (unit bookkeeping
                                               columns dropped) against a study's own CSV

The timing columns (wall_s, wall_s_* and repeats, whose count follows the measured times; and,
with --run, unit, unit_rows, unit_status, unit_message) are left out; every other field must be
equal as text. Prints one line per file and exits 1 on a difference.

`stiffbench compare OLD NEW` (docs/commands/compare.md) is the full comparison of two result
folders: rows matched by their keys, a tolerance on reals, ratios, run records and wall-time
verdicts.
"""
import csv
import os
import sys

IGNORED = {"wall_s", "repeats"}
RUN_COLUMNS = {"unit", "unit_rows", "unit_status", "unit_message"}


def read(path, drop):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return [], []
    keep = [i for i, c in enumerate(rows[0]) if c not in drop and not c.startswith("wall_s_")]
    return [rows[0][i] for i in keep], [[r[i] for i in keep] for r in rows[1:]]


def compare(old, new, drop_old, drop_new, label):
    h1, r1 = read(old, drop_old)
    h2, r2 = read(new, drop_new)
    if h1 != h2:
        print(f"DIFF {label}: columns {h1} != {h2}")
        return False
    if len(r1) != len(r2):
        print(f"DIFF {label}: {len(r1)} rows != {len(r2)} rows")
        return False
    for k, (a, b) in enumerate(zip(r1, r2)):
        if a != b:
            cols = [h1[i] for i in range(len(a)) if a[i] != b[i]]
            print(f"DIFF {label}: row {k + 1} differs in {cols}: {a} != {b}")
            return False
    print(f"same {label} ({len(r1)} rows, {len(h1)} columns compared)")
    return True


def main(argv):
    if len(argv) == 4 and argv[1] == "--run":
        ok = compare(argv[2], argv[3], IGNORED | RUN_COLUMNS, IGNORED, argv[2])
        return 0 if ok else 1
    if len(argv) != 3:
        print(__doc__)
        return 2
    old_dir, new_dir = argv[1], argv[2]
    ok, n = True, 0
    for root, _, files in os.walk(old_dir):
        for name in sorted(files):
            if not name.endswith(".csv") or root.endswith("reference"):
                continue
            rel = os.path.relpath(os.path.join(root, name), old_dir)
            other = os.path.join(new_dir, rel)
            n += 1
            if not os.path.exists(other):
                print(f"MISSING {rel} in {new_dir}")
                ok = False
                continue
            ok = compare(os.path.join(root, name), other, IGNORED, IGNORED, rel) and ok
    print(f"{n} CSV file(s) compared: {'all equal' if ok else 'DIFFERENCES'} (timing columns ignored)")
    return 0 if ok and n > 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
