#!/usr/bin/env python3
"""Runs every shell block of the documentation, as written, in a scratch copy of the repository.

    python3 scripts/check-doc-commands.py            # README.md, docs/guide.md, docs/scoring.md, python/README.md
    python3 scripts/check-doc-commands.py README.md  # one page
    OEG_DOCS_VENV=target/python-ci python3 scripts/check-doc-commands.py   # with a venv that has the package

Each ```sh block of the pages runs in order, in one scratch copy of the tracked files (so a block may use the
files an earlier one wrote), with `../shared/data` beside it when the shared data set is present. A command
fails the check when it exits with another status than its comment states (0 unless `# exits N`), or when a
result its comment states does not hold:

    # writes out/default/report.html      each path named after "writes" exists afterwards
    # prints "path found"                 standard output or error contains the text

What is not run, each with its reason printed:
- `cargo test`: CI runs the test command as its own step;
- a command that reads `../shared/data` when the shared data set is absent;
- with OEG_DOCS_VENV (a virtual environment where `pip install ./python` already ran on this tree):
  `python3 -m venv .venv` links `.venv` to it instead, and `pip install` leaves out `./python`.

`cargo run --release [-- ARGS]` runs target/release/oeg ARGS (build it first: `cargo build --release`), and
`oeg` is that binary too: the commands run what this tree built, without a second build in the scratch copy.
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAGES = ["README.md", "docs/guide.md", "docs/scoring.md", "python/README.md"]
TIMEOUT_S = 1200


def blocks(page):
    """The shell blocks of a Markdown page: (line of the first command, [(line, command, comment)])."""
    out, current, start = [], None, 0
    with open(os.path.join(ROOT, page), encoding="utf-8") as f:
        lines = f.read().split("\n")
    k = 0
    while k < len(lines):
        line = lines[k]
        if current is None and re.match(r"^```(sh|bash|shell)\s*$", line):
            current, start = [], k + 2
        elif current is not None and line.startswith("```"):
            out.append((start, current))
            current = None
        elif current is not None:
            number = k + 1
            text = line
            while text.rstrip().endswith("\\") and k + 1 < len(lines):
                k += 1
                text = text.rstrip()[:-1] + " " + lines[k].strip()
            command, comment = split_comment(text)
            if command.strip():
                current.append((number, command.strip(), comment))
        k += 1
    return out


def split_comment(text):
    """A shell line split at its first `#` outside quotes that starts a word."""
    quote = None
    for k, ch in enumerate(text):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (k == 0 or text[k - 1].isspace()):
            return text[:k], text[k + 1 :].strip()
    return text, ""


def stated(comment):
    """What a command's comment says must hold: (paths written, texts printed, exit status)."""
    written = []
    for match in re.finditer(r"\bwrites ([^;#]+)", comment):
        for word in re.split(r",\s*|\s+and\s+|\s+", match.group(1)):
            word = word.strip().rstrip(".")
            if "/" in word and not word.startswith("-"):
                written.append(word)
    printed = re.findall(r'\bprints "([^"]+)"', comment)
    status = re.search(r"\bexits (\d+)", comment)
    return written, printed, int(status.group(1)) if status else 0


def shim(path, body):
    with open(path, "w", encoding="utf-8") as f:
        f.write("#!/bin/sh\n" + body)
    os.chmod(path, 0o755)


def main(argv):
    sys.stdout.reconfigure(line_buffering=True)
    pages = argv or PAGES
    oeg = os.path.join(ROOT, "target", "release", "oeg")
    if not os.path.isfile(oeg):
        print(f"docs-commands: {oeg} is missing: run `cargo build --release` first", file=sys.stderr)
        return 1
    venv = os.environ.get("OEG_DOCS_VENV")
    venv = os.path.abspath(venv) if venv else None
    shared_data = os.environ.get("OEG_SHARED_DATA") or os.path.join(os.path.dirname(ROOT), "shared", "data")
    have_shared = os.path.isdir(shared_data)

    scratch = tempfile.mkdtemp(prefix="oeg-docs-")
    project = os.path.join(scratch, "project")
    tracked = subprocess.run(
        ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True
    ).stdout.decode().split("\0")
    for name in filter(None, tracked):
        source = os.path.join(ROOT, name)
        if os.path.isfile(source):
            os.makedirs(os.path.dirname(os.path.join(project, name)), exist_ok=True)
            shutil.copy2(source, os.path.join(project, name))
    if have_shared:
        os.makedirs(os.path.join(scratch, "shared"))
        os.symlink(os.path.abspath(shared_data), os.path.join(scratch, "shared", "data"))
    bin_dir = os.path.join(scratch, "bin")
    os.makedirs(bin_dir)
    real_cargo = shutil.which("cargo") or "cargo"
    shim(
        os.path.join(bin_dir, "cargo"),
        f"""# `cargo run --release [-- ARGS]` is the release binary this tree built; any other cargo command is cargo.
if [ "$1" = run ] && [ "$2" = --release ]; then
    shift 2
    [ "$1" = -- ] && shift
    exec {shlex.quote(oeg)} "$@"
fi
if [ "$1" = build ] && [ "$2" = --release ]; then exit 0; fi
exec {shlex.quote(real_cargo)} "$@"
""",
    )
    shim(os.path.join(bin_dir, "oeg"), f'exec {shlex.quote(oeg)} "$@"\n')
    path = bin_dir + os.pathsep + (os.path.join(venv, "bin") + os.pathsep if venv else "") + os.environ["PATH"]
    env = dict(os.environ, PATH=path, OEG_BIN=oeg)
    env.pop("OEG_SHARED_DATA", None)
    has_numpy = (
        subprocess.run(["python3", "-c", "import numpy"], env=env, capture_output=True).returncode == 0
    )

    failures, ran, skipped, total_s, passed, unwritten = [], 0, 0, 0.0, {}, []
    for page in pages:
        for _, commands in blocks(page):
            for line, command, comment in commands:
                where = f"{page}:{line}"
                reason, as_written = None, command
                if command.startswith("cargo test"):
                    reason = "CI runs the test command as its own step"
                elif "../shared/data" in command and not have_shared:
                    reason = f"the shared data set is absent ({shared_data})"
                    # What it would have written is missing too: the commands that read it are skipped.
                    unwritten.extend(re.findall(r"--out[ =](\S+)", command))
                elif any(re.search(re.escape(out) + r"(/|\s|$)", command) for out in unwritten):
                    reason = "it reads what a skipped command would have written"
                elif "npy_planner.py" in command and not has_numpy:
                    reason = "python3 has no numpy (set OEG_DOCS_VENV to a venv with it)"
                elif venv and re.match(r"^python3 -m venv \.venv\b", command):
                    rest = command.split("&&", 1)
                    if not os.path.lexists(os.path.join(project, ".venv")):
                        os.symlink(venv, os.path.join(project, ".venv"))
                    if len(rest) == 1:
                        reason = f".venv is {venv}, where CI installed ./python"
                    else:
                        command = rest[1].strip()
                if venv and reason is None and "pip install" in command and "./python" in command:
                    words = [w for w in shlex.split(command) if w != "./python"]
                    command = shlex.join(words) if words[-1] != "install" else ""
                    if not command:
                        reason = f"./python is already installed in {venv} from this tree"
                # The same command as one that already ran and held, in the same copy (the guide repeats the
                # README): the same files and output, so it is not run twice.
                key = re.sub(r"^cargo run --release --\s*", "oeg ", command).strip()
                if reason is None and key in passed:
                    reason = f"the same command ran and held at {passed[key]}"
                if reason:
                    print(f"skip  {where}  {as_written}\n      ({reason})")
                    skipped += 1
                    continue
                written, printed, status = stated(comment)
                start = time.monotonic()
                try:
                    done = subprocess.run(
                        ["bash", "-c", command],
                        cwd=project,
                        env=env,
                        capture_output=True,
                        timeout=TIMEOUT_S,
                    )
                    output = done.stdout.decode(errors="replace") + done.stderr.decode(errors="replace")
                    code = done.returncode
                except subprocess.TimeoutExpired:
                    output, code = f"timed out after {TIMEOUT_S} s", None
                seconds = time.monotonic() - start
                total_s += seconds
                ran += 1
                problems = []
                if code != status:
                    problems.append(f"exit status {code}, expected {status}")
                problems += [f"{p} was not written" for p in written if not os.path.exists(os.path.join(project, p))]
                problems += [f'the output does not contain "{t}"' for t in printed if t not in output]
                shown = command if command == as_written else f"{command}   (as written: {as_written})"
                print(f"{'FAIL' if problems else 'ok  '}  {seconds:6.1f} s  {where}  {shown}")
                if not problems:
                    passed.setdefault(key, where)
                if problems:
                    failures.append(where)
                    for p in problems:
                        print(f"      {p}")
                    print("      " + "\n      ".join(output.strip().split("\n")[-25:]))
    print(
        f"docs-commands: {ran} commands run in {total_s:.0f} s, {skipped} skipped, {len(failures)} failed"
        + (f": {', '.join(failures)}" if failures else "")
    )
    if failures:
        print(f"docs-commands: the scratch copy is kept for a look: {scratch}")
        return 1
    shutil.rmtree(scratch, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
