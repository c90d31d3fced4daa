#!/usr/bin/env python3
"""Every shipped scenario with a controller fails when its controller does nothing.

  hold_fails_test.py VLAB SOURCE_DIR OUT_DIR

For each scenes/*.yaml and cases/*/*.yaml that has a `controller:`, the test writes a
copy into OUT_DIR with the controller taken out, so the lab's devices hold (an arm holds
its initial position until a first command, docs/scenarios.md), runs it with `vlab run`
and asserts that at least one check fails on samples it saw: a check that the lab's own
ground truth decides (docs/testing.md). The copy differs from the scenario only in:
- no `controller:` block, and no check on a `controller.*` or `task.*` signal (those
  columns are the controller's own, or a task program's, and are gone with it);
- no `outputs:` block (its plots may read a CSV the controller writes); log.csv stays;
- `scene:` as an absolute path, so the copy loads the same scene;
- a realtime clock becomes the fast clock (cases/yoyo/stage3): the realtime clock only
  paces the wall so that an outside controller keeps up; with no controller the lab
  computes the same periods either way, and the held run need not take 46 s.
Skipped: a scenario with a line `# hold passes: REASON` (the test prints the reason).
Exit 0 when every scenario behaves, 1 otherwise (each failure printed).
"""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

TOP_KEY = re.compile(r"^[A-Za-z_][A-Za-z_0-9]*:")


def value(check):
    return "NaN" if check["value"] is None else f"{check['value']:.6g}"


def held_copy(text, scenario_dir):
    """The scenario text without its controller, its controller checks and its outputs."""
    out, skipping = [], False
    for line in text.splitlines():
        if TOP_KEY.match(line):
            skipping = line.startswith("controller:") or line.startswith("outputs:")
            if line.startswith("scene:"):
                scene = line.split(":", 1)[1].split("#", 1)[0].strip().strip("\"'")
                line = "scene: " + json.dumps(str((scenario_dir / scene).resolve()))
        if skipping or re.search(r"signal:\s*(controller|task)\.", line):
            continue
        if re.match(r"^clock:\s*realtime\b", line):
            line = "clock: fast  # held copy of a realtime scenario: nothing outside to keep pace with"
        out.append(line)
    return "\n".join(out) + "\n"


def main():
    vlab, source, out_dir = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
    out_dir.mkdir(parents=True, exist_ok=True)
    scenarios = sorted(source.glob("scenes/*.yaml")) + sorted(source.glob("cases/*/*.yaml"))
    failures, tested = [], 0
    for path in scenarios:
        text = path.read_text()
        name = path.relative_to(source).as_posix()
        if not re.search(r"^controller:", text, re.M):
            print(f"{name}: no controller (the lab holds in its plain run already)")
            continue
        marker = re.search(r"^#\s*hold passes:\s*(.*)$", text, re.M)
        if marker:
            print(f"{name}: holding passes: {marker.group(1)}")
            continue
        stem = name.replace("/", "_").removesuffix(".yaml")
        copy = out_dir / f"{stem}_held.yaml"
        copy.write_text(held_copy(text, path.parent))
        run_dir = out_dir / f"{stem}_held"
        result = subprocess.run([str(vlab), "run", str(copy), "--quiet", "--out", str(run_dir)],
                                capture_output=True, text=True, timeout=600)
        tested += 1
        summary_file = run_dir / "summary.json"
        if result.returncode != 1 or not summary_file.exists():
            failures.append(f"{name}: held run exited {result.returncode}, expected 1 (a failed check): "
                            f"{result.stderr.strip()[-400:]}")
            continue
        checks = json.loads(summary_file.read_text())["checks"]
        # a failure on samples it saw, not an empty window
        caught = [c for c in checks if not c["pass"] and c["samples"] > 0]
        if caught:
            print(f"{name}: held, fails " +
                  ", ".join(f"{c['name']} ({value(c)})" for c in caught))
        else:
            failures.append(f"{name}: held, no check failed on its samples: " +
                            ", ".join(f"{c['name']} {value(c)} ({c['samples']} samples)" for c in checks))
    for f in failures:
        print("FAIL " + f)
    if tested == 0:
        print("FAIL no scenario tested")
        return 1
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
