#!/usr/bin/env python3
"""Runs the Lua examples of docs/tasks.md, each in its scenario, with `vlab run`.

Usage: doc_examples.py VLAB SOURCE_DIR WORK_DIR

Blocks of docs/tasks.md, by their fence tag:
  ```lua            runs alone: one script
  ```lua continued  runs after the blocks before it, back to the last ```lua block (the
                    tutorial's steps): the chain runs once, at its last block
  ```lua-fragment   not run (it needs a vision program, or names undefined frames)
An HTML comment on the line just above a ```lua block names the scenario of its chain,
relative to the source folder: <!-- scenario: tests/data/task/tutorial_gripper.yaml -->;
without one the chain runs in tests/task/doc_examples.yaml (the PA10 with its JR3).

Each chain becomes one script whose line N is line N of docs/tasks.md (the lines outside
the chain's blocks blank), so a script error's FILE:LINE is the line in the manual. A chain
fails when `vlab run` fails (a script error, or a failed check: every scenario checks that
the program ended); the message names the block's first line in docs/tasks.md.
"""
import os
import re
import subprocess
import sys

DEFAULT_SCENARIO = "tests/task/doc_examples.yaml"


def chains(doc_lines):
    """Yields (scenario, [(first_line, [lines])...]) for every chain of runnable blocks."""
    chain, scenario = None, None
    i = 0
    while i < len(doc_lines):
        m = re.match(r"^```(\S*)\s*(\S*)\s*$", doc_lines[i])
        if not m or not m.group(1):
            i += 1
            continue
        tag, more = m.group(1), m.group(2)
        body_start = i + 1
        j = body_start
        while j < len(doc_lines) and not doc_lines[j].startswith("```"):
            j += 1
        block = (body_start + 1, doc_lines[body_start:j])  # 1-based first line of the code
        if tag == "lua" and more == "continued":
            if chain is None:
                raise SystemExit("docs/tasks.md:%d: a ```lua continued block with no ```lua block before it" % (i + 1))
            chain.append(block)
        elif tag == "lua":
            if chain:
                yield scenario, chain
            chain = [block]
            above = doc_lines[i - 1] if i > 0 else ""
            s = re.match(r"^<!--\s*scenario:\s*(\S+)\s*-->\s*$", above)
            scenario = s.group(1) if s else DEFAULT_SCENARIO
        i = j + 1
    if chain:
        yield scenario, chain


def main():
    vlab, source, work = sys.argv[1:4]
    doc_path = os.path.join(source, "docs", "tasks.md")
    with open(doc_path, encoding="utf-8") as f:
        doc_lines = f.read().split("\n")
    os.makedirs(work, exist_ok=True)
    failures = 0
    count = 0
    for scenario, chain in chains(doc_lines):
        count += 1
        first = chain[0][0]
        last = chain[-1][0]
        # the script: docs line N at script line N
        script = [""] * len(doc_lines)
        for start, lines in chain:
            for k, text in enumerate(lines):
                script[start - 1 + k] = text
        name = "tasks.md.%d.lua" % first
        path = os.path.abspath(os.path.join(work, name))
        with open(path, "w", encoding="utf-8") as f:
            f.write("\n".join(script).rstrip() + "\n")
        out = os.path.join(work, "out_%d" % first)
        cmd = [vlab, "run", os.path.join(source, scenario), "-q", "--out", out,
               "--set", "controller.programs.0.script=" + path]
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        where = "docs/tasks.md:%d" % first + ("" if last == first else " (to the block at line %d)" % last)
        if p.returncode != 0:
            failures += 1
            text = p.stdout.replace(path, "docs/tasks.md")
            print("FAIL %s in %s (exit %d):\n%s" % (where, scenario, p.returncode, text))
        else:
            print("ok   %s in %s" % (where, scenario))
    if count == 0:
        print("no ```lua blocks found in docs/tasks.md")
        return 1
    print("%d of %d examples failed" % (failures, count) if failures else "all %d examples ran" % count)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
