#!/usr/bin/env python3
"""The ratchet on size: no Rust function over 100 lines and no Rust file over 500 lines, outside the committed
allow-list scripts/size-allowlist.txt, which may only shrink. Run by CI (`.ci/run`).

    python3 scripts/check-size.py            # check every tracked .rs file
    python3 scripts/check-size.py --update   # rewrite the list's sizes after a listed item shrank

The check fails when:
- a function or a file over its bound is not in the list (split it: a new item never joins the list);
- a listed item grew past the size the list records;
- a listed item shrank (update the list: `--update`) or is within its bound now (`--update` drops it).

`--update` only lowers sizes and drops entries: it never adds an item or raises a size.

A function is counted from its `fn` line to the line of its closing brace; braces in strings, characters and
comments are ignored. A function is named by its file and name, with `#2`, `#3`, ... for later functions of
the same name in one file.
"""

import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LIST = os.path.join(ROOT, "scripts", "size-allowlist.txt")
MAX_FN_LINES = 100
MAX_FILE_LINES = 500
FN = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:const\s+)?(?:async\s+)?(?:unsafe\s+)?(?:extern\s+\"[^\"]*\"\s+)?fn\s+(\w+)")


def code_only(line, state):
    """`line` with strings, characters and comments blanked; `state` carries an open block comment or string."""
    out, k = [], 0
    while k < len(line):
        c = line[k]
        if state["block"]:
            if line.startswith("*/", k):
                state["block"] -= 1
                k += 2
            elif line.startswith("/*", k):
                state["block"] += 1
                k += 2
            else:
                k += 1
            continue
        if state["string"]:
            if c == "\\":
                k += 2
            elif c == '"':
                state["string"] = False
                k += 1
            else:
                k += 1
            continue
        if line.startswith("//", k):
            break
        if line.startswith("/*", k):
            state["block"] += 1
            k += 2
        elif c == '"':
            state["string"] = True
            k += 1
        elif c == "'" and re.match(r"'(\\.|[^\\'])'", line[k:]):
            k += len(re.match(r"'(\\.|[^\\'])'", line[k:]).group(0))
        else:
            out.append(c)
            k += 1
    return "".join(out)


def measure(path):
    """The file's line count and its functions: [(name, lines)]."""
    with open(os.path.join(ROOT, path), encoding="utf-8") as f:
        lines = f.read().split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    state = {"block": 0, "string": False}
    code = [code_only(line, state) for line in lines]
    functions = []
    for start, line in enumerate(lines):
        m = FN.match(line)
        if not m or state_in_comment(lines, start):
            continue
        depth, opened, end = 0, False, None
        for k in range(start, len(code)):
            for c in code[k]:
                if c == "{":
                    depth += 1
                    opened = True
                elif c == "}":
                    depth -= 1
                elif c == ";" and not opened and depth == 0:
                    end = -1
                    break
            if end is not None or (opened and depth == 0):
                end = k if end is None else end
                break
        if end is not None and end >= 0:
            functions.append((m.group(1), end - start + 1))
    return len(lines), functions


def state_in_comment(lines, k):
    return lines[k].lstrip().startswith("//")


def oversized():
    """Every item over its bound: {key: lines}."""
    files = subprocess.run(
        ["git", "ls-files", "*.rs"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    items = {}
    for path in files:
        if not os.path.isfile(os.path.join(ROOT, path)):
            continue
        num_lines, functions = measure(path)
        if num_lines > MAX_FILE_LINES:
            items[f"file {path}"] = num_lines
        seen = {}
        for name, n in functions:
            seen[name] = seen.get(name, 0) + 1
            if n > MAX_FN_LINES:
                suffix = f"#{seen[name]}" if seen[name] > 1 else ""
                items[f"fn {path}::{name}{suffix}"] = n
    return items


def read_list():
    listed = {}
    with open(LIST, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            key, _, size = line.rpartition(" ")
            if not key.startswith(("file ", "fn ")) or not size.isdigit():
                sys.exit(f"{LIST}:{number}: expected `file PATH LINES` or `fn PATH::NAME LINES`, got `{line}`")
            listed[key] = int(size)
    return listed


def main():
    update = "--update" in sys.argv[1:]
    now, listed = oversized(), read_list()
    problems, kept = [], {}
    for key, n in sorted(now.items()):
        bound = MAX_FILE_LINES if key.startswith("file ") else MAX_FN_LINES
        if key not in listed:
            problems.append(f"{key}: {n} lines, over {bound} and not in the list: split it")
        elif n > listed[key]:
            problems.append(f"{key}: grew from {listed[key]} to {n} lines (over {bound}): split it")
            kept[key] = listed[key]
        else:
            if n < listed[key] and not update:
                problems.append(f"{key}: shrank from {listed[key]} to {n} lines: record it (--update)")
            kept[key] = n
    for key in sorted(set(listed) - set(now)):
        if not update:
            problems.append(f"{key}: within its bound now: drop it from the list (--update)")
    if update:
        header = []
        with open(LIST, encoding="utf-8") as f:
            header = [line for line in f if line.startswith("#")]
        with open(LIST, "w", encoding="utf-8") as f:
            f.writelines(header)
            for key in sorted(kept):
                f.write(f"{key} {kept[key]}\n")
        print(f"{LIST}: {len(kept)} items")
    for p in problems:
        print(f"size: {p}", file=sys.stderr)
    if problems:
        sys.exit(1)
    print(f"size: {len(now)} items over their bounds, all listed; none grew")


if __name__ == "__main__":
    main()
