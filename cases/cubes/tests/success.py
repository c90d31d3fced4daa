#!/usr/bin/env python3
"""Success of the lettered-cubes task over seeds (issue 16: stage 1 >= 19/20, stage 2 >= 17/20).

  success.py VLAB OUT_DIR [FIRST_SEED [COUNT [SCENARIO]]] [--min N]   defaults 1, 20, cases/cubes/stage1.yaml

Runs the scenario once per seed (`vlab run SCENARIO --seed N`), then prints one row per seed:
pass/fail, the failed checks (the cause), and the simulated time of each letter: the time at
which the letter's cube came to within 5 mm of its slot for good (the word device's
word.L.pos_error, log.csv) minus the previous such time (the first from t = 0, so it includes the first look),
in the order the letters came (a letter that VERIFY took out of its slot and set back comes last),
and the run's final errors: the worst letter's distance from its slot (mm) and reading-direction
error (deg), the log's last row. The word is the word device's: its letters in the order of their
log columns. Last, the success count, the median and range of the time per letter, the worst and
median final distance of the passing runs' letters, and the wall time per run. Exit 0 when
every run was made (whatever their verdicts) and, with --min N, at least N passed; 1 when
fewer passed; 2 on bad arguments.
"""
import csv
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

IN_SLOT = 0.005  # m, the checks' bound (stage1.yaml, stage2.yaml: word.L.pos_error)


def word_of(head):
    """The word device's letters, in the order of their log columns word.L.pos_error."""
    return "".join(c[len("word."):-len(".pos_error")] for c in head
                   if c.startswith("word.") and c.endswith(".pos_error"))


def letter_times(log_path):
    """Per letter, the time (s) its cube entered its slot for good; None if it never did."""
    with open(log_path, newline="") as f:
        rows = list(csv.reader(f))
    head, rows = rows[0], rows[1:]
    t = [float(r[0]) for r in rows]
    out = []
    for letter in word_of(head):
        col = head.index(f"word.{letter}.pos_error")
        entered = None
        for i, r in enumerate(rows):
            inside = float(r[col]) <= IN_SLOT
            if inside and entered is None:
                entered = t[i]
            elif not inside:
                entered = None
        out.append(entered)
    return out


def final_errors(log_path):
    """Per letter, the last row's distance from its slot (m) and reading-direction error (deg)."""
    with open(log_path, newline="") as f:
        rows = list(csv.reader(f))
    head, last = rows[0], rows[-1]
    return [(float(last[head.index(f"word.{c}.pos_error")]), float(last[head.index(f"word.{c}.yaw_error")]))
            for c in word_of(head)]


def main():
    args, minimum = sys.argv[1:], None
    if "--min" in args:
        i = args.index("--min")
        minimum = int(args[i + 1])
        del args[i:i + 2]
    if len(args) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    vlab, out = args[0], Path(args[1])
    first = int(args[2]) if len(args) > 2 else 1
    count = int(args[3]) if len(args) > 3 else 20
    scenario = args[4] if len(args) > 4 else "cases/cubes/stage1.yaml"
    passed, per_letter, walls, finals = 0, [], [], []
    print(f"{'seed':>4}  {'verdict':7}  {'s per letter, as they came':28}  {'worst mm, deg':14}  cause")
    for seed in range(first, first + count):
        folder = out / f"seed{seed}"
        start = time.monotonic()
        run = subprocess.run([vlab, "run", scenario, "--seed", str(seed), "--quiet", "--out", str(folder)],
                             capture_output=True, text=True)
        walls.append(time.monotonic() - start)
        summary = folder / "summary.json"
        cause = ""
        if summary.exists():
            s = json.loads(summary.read_text())
            failed = [c["name"] for c in s.get("checks", []) if not c.get("pass")]
            cause = ", ".join(failed)
            if s.get("failure"):
                cause = (cause + "; " if cause else "") + str(s["failure"])[:100]
        if run.returncode != 0 and not cause:
            lines = [l for l in (run.stderr or "").splitlines() if l.strip()]
            cause = lines[0][:100] if lines else f"exit {run.returncode}"
        ok = run.returncode == 0
        passed += ok
        times = letter_times(folder / "log.csv") if (folder / "log.csv").exists() else []
        steps, prev = [], 0.0
        for t in sorted(t for t in times if t is not None):
            steps.append(t - prev)
            prev = t
        errors = final_errors(folder / "log.csv") if (folder / "log.csv").exists() else []
        if ok:
            per_letter += steps
            finals += [d for d, _ in errors]
        text = " ".join(f"{x:5.1f}" for x in steps)
        worst = (f"{max(d for d, _ in errors) * 1000:5.1f} {max(a for _, a in errors):6.2f}" if errors else "")
        print(f"{seed:4d}  {'pass' if ok else 'FAIL':7}  {text:28}  {worst:14}  {cause}", flush=True)
    median = statistics.median(per_letter) if per_letter else float("nan")
    span = f" ({min(per_letter):.1f}-{max(per_letter):.1f})" if per_letter else ""
    print(f"success {passed}/{count}; time per letter {median:.1f} s median{span} simulated (passing runs); "
          f"wall time per run {statistics.median(walls):.0f} s median")
    if finals:
        print(f"final distance from the slot: worst {max(finals) * 1000:.1f} mm, median "
              f"{statistics.median(finals) * 1000:.1f} mm ({len(finals)} letters of the passing runs)")
    return 1 if minimum is not None and passed < minimum else 0


if __name__ == "__main__":
    sys.exit(main())
