#!/usr/bin/env python3
"""Every command in README.md and docs/*.md, run or checked (ctest runs it as docs.commands).

Each fenced ```sh or ```bash block runs with bash (set -e -o pipefail) from a throwaway copy of the
repository root (a link to each of its entries; build is the build folder given), with
SHUTTERLAB_DATA_DIR and data set to the shared data folder and every /tmp/ rewritten to a temporary
folder of the Markdown file's own: a file's blocks run in order, each seeing what the earlier ones
wrote and nothing of another file's. A command whose comment says "# exit code N" must exit N. A
line that starts with # is output shown to the reader (bash skips it as a comment).

A block that cannot run here says why on the line before its fence:
  <!-- doc-test: template -->   placeholders in capitals (DATASET, PHOTOS, LOG)
  <!-- doc-test: hardware -->   SPI, GPIO, sudo
  <!-- doc-test: long; suite: A => B; C => D -->
                                over about 60 s on 2 cores: the suite runs it smaller, each text A
                                of the block's commands (not its comments) replaced by B (a
                                count, a duration, a --max-frames added; neither holds ';');
                                --long runs it as written
and a block of any language that the commands read as a file says which, the same way:
  <!-- doc-test: file /tmp/camera.json -->   written there before the file's first block runs
A block that runs sudo, scripts/setup.sh or scripts/test.sh is never run, marked or not: it would
install packages, build, or run this test again. A block that names a benchmark this build lacks
(SHUTTERLAB_BUILD_BENCH off) is not run, nor are the blocks after it in its file (they may read what
it writes). A command that exits 77, a script saying that a tool it needs is missing
(scripts/slurm_cluster.sh without Slurm), ends its block as a skip, said in one line; under CI=true
that is a failure. A line that starts a doc-test mark but is none of these is reported. Every
command of every block, and every command or synopsis quoted inline in the prose and tables
(`build/bin/shutterlab ...`, `shutterlab SUB [--a X | --b]`), is also checked cheaply: each
scripts/X and build/bin/X it names exists (a benchmark may be missing from a build that has
SHUTTERLAB_BUILD_BENCH off), and each shutterlab command names a subcommand, and options, that
`build/bin/shutterlab SUBCOMMAND --help` lists. A fence with no language whose lines start with a
command is reported: tag it sh.

Usage: scripts/doc_commands.py [--build DIR] [--long] [--verbose] [--keep] [--root DIR] [FILE.md..]
  --build DIR  the build folder whose bin/ the commands run (default: ROOT/build)
  --long       run the blocks marked long as written (not smaller): hours
  --verbose    print each block's time (and why a block is not run)
  --keep       keep the temporary folders (their path is printed)
  --root DIR   the repository (default: this script's); FILE.md default: README.md, docs/*.md
  --timeout S  the seconds a block may run (default 600)
(stdlib only; run from anywhere.) Exit 0 when every command holds, 1 with one line per failing
block or command (FILE:LINE: command: exit code: the last lines of its stderr), 77 (a ctest skip)
when the shared data folder is missing, after the cheap checks (under CI=true that is a failure),
2 on bad usage.
"""
import argparse
import glob
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SKIP = 77  # ctest's SKIP_RETURN_CODE for this test, and a script's "a tool I need is missing"
MARKER = re.compile(r"^\s*<!--\s*doc-test:\s*([\w-]+)(?:\s+(\S+))?\s*-->\s*$")
MARKS = ("template", "hardware", "long", "file")
ANY_MARK = re.compile(r"^\s*<!--\s*doc-test\b")
# A long block's smaller run in the suite: "long; suite: A => B; C => D".
LONG = re.compile(r"^\s*<!--\s*doc-test:\s*long\s*;\s*suite:\s*(.+?)\s*-->\s*$")
FENCE_OPEN = re.compile(r"^(\s*)```\s*([\w-]*)\s*$")
FENCE_CLOSE = re.compile(r"^\s*```\s*$")
EXIT_CODE = re.compile(r"\s#\s*exit code (\d+)\s*$")
NEVER_RUN = re.compile(r"(^|[\s;&|(])(sudo|scripts/setup\.sh|scripts/test\.sh)(\s|$)")
NAMED = re.compile(r"(?<![\w./$-])((?:scripts|build/bin)/[\w.+-]*\w)")
SHUTTERLAB = re.compile(r"(?<![\w./$-])(?:build/bin/)?shutterlab(?=$|[\s\"')`])([^|;&<>\"')`]*)")
TMP = re.compile(r"(?<![\w./$-])/tmp/")
SHARED = re.compile(r"(?<![\w./$-])\.\./shared/data")
COMMAND_LINE = re.compile(r"\s*(build/bin|scripts)/[\w.+-]*\w(\s|$)")
COMMENT = re.compile(r"(^|\s)#.*$")
STDERR_LINES = 3
HEADER = [  # the lines before the block's own: ERR and __expect write "LINE STATUS EXPECTED|-"
    "set -e -o pipefail",
    "trap '__s=$?; echo \"$LINENO $__s -\" >\"$DOC_TEST_STATUS\"' ERR",
    "__expect() { [ \"$2\" = \"$1\" ] || { echo \"$3 $2 $1\" >\"$DOC_TEST_STATUS\"; exit 1; }; }",
]


class Block:
    def __init__(self, path, line, lang, mark, lines, smaller=()):
        self.path = path  # as shown, relative to the root
        self.line = line  # the fence's line, 1-based
        self.lang = lang
        self.mark = mark
        self.lines = lines  # the block's lines, the fence's indentation removed
        self.smaller = list(smaller)  # a long block's (text, replacement) pairs for the suite

    def resized(self):
        """The block as the suite runs it: each text of a long block's pairs replaced in its
        commands, not in its comments."""
        lines = []
        for t in self.lines:
            code = command_part(t)
            comment = t[len(code):]
            for text, replacement in self.smaller:
                code = code.replace(text, replacement)
            lines.append(code + comment)
        return Block(self.path, self.line, self.lang, self.mark, lines)

    def commands(self):
        """(first line, last line, text): each command, continued lines joined, with its lines."""
        out, start, parts = [], None, []
        for i, text in enumerate(self.lines):
            number = self.line + 1 + i
            if start is None:
                start = number
            if text.endswith("\\"):
                parts.append(text[:-1])
                continue
            parts.append(text)
            out.append((start, number, " ".join(p.strip() for p in parts)))
            start, parts = None, []
        if parts:
            out.append((start, self.line + len(self.lines), " ".join(p.strip() for p in parts)))
        return out


def command_part(line):
    """The line before its comment: "" for a line that starts with #."""
    if line.lstrip().startswith("#"):
        return ""
    m = COMMENT.search(line)
    return line[:m.start()] if m else line


def read_mark(line, body):
    """(kind, file path, a long block's (text, replacement) pairs, finding or None) of the line
    before a block whose lines are body; kind None when the line is no mark."""
    mark, long_mark = MARKER.match(line), LONG.match(line)
    if long_mark:
        smaller, commands = [], [command_part(t) for t in body]
        for pair in long_mark.group(1).split(";"):
            text, arrow, replacement = pair.partition("=>")
            if not arrow or not text.strip() or not any(text.strip() in c for c in commands):
                return "long", None, [], (f"'{pair.strip()}' is not TEXT => REPLACEMENT with "
                                          f"TEXT in a command of the block below")
            smaller.append((text.strip(), replacement.strip()))
        return "long", None, smaller, None
    kind, file_path = (mark.group(1), mark.group(2)) if mark else (None, None)
    if kind == "long":
        return kind, None, [], ("a long block says how the suite runs it smaller: "
                                "<!-- doc-test: long; suite: TEXT => REPLACEMENT -->")
    if (kind is None and ANY_MARK.match(line)) or (
            kind is not None and (kind not in MARKS or (kind == "file") != bool(file_path))):
        return "unknown", None, [], (f"unknown mark '{line.strip()}' (template, hardware, "
                                     f"long; suite: A => B, or file PATH)")
    return kind, file_path, [], None


def read_markdown(root, path):
    """The file's shell blocks, its blocks to save as files ({path: text}), its inline code
    spans ((line, text) of each), and its findings."""
    with open(os.path.join(root, path), encoding="utf-8") as f:
        lines = f.read().split("\n")
    blocks, saved, spans, findings = [], {}, [], []
    i = 0
    while i < len(lines):
        m = FENCE_OPEN.match(lines[i])
        if not m:
            for span in re.findall(r"`([^`\n]+)`", lines[i]):
                spans.append((i + 1, span.replace("\\|", "|")))
            i += 1
            continue
        indent, lang = len(m.group(1)), m.group(2)
        j = i + 1
        while j < len(lines) and not FENCE_CLOSE.match(lines[j]):
            j += 1
        body = [text[indent:] if text[:indent].strip() == "" else text for text in lines[i + 1:j]]
        k = next((k for k in range(i - 1, -1, -1) if lines[k].strip()), 0)
        kind, file_path, smaller, finding = read_mark(lines[k], body)
        if finding:  # a block with a mark that is not understood is not run
            findings.append(f"{path}:{k + 1}: {finding}")
        elif kind == "file":
            saved[file_path] = "\n".join(body) + "\n"
        elif lang in ("sh", "bash"):
            blocks.append(Block(path, i + 1, lang, kind, body, smaller))
        elif lang == "" and any(COMMAND_LINE.match(t) for t in body):
            findings.append(f"{path}:{i + 1}: a command in a fence with no language: tag it ```sh")
        i = j + 1
    return blocks, saved, spans, findings


class Checker:
    """The cheap checks: named files exist, shutterlab's subcommands and options exist."""

    def __init__(self, root, build):
        self.root, self.build = root, build
        self.binary = os.path.join(build, "bin", "shutterlab")
        self.helps = {}
        cache = os.path.join(build, "CMakeCache.txt")
        text = open(cache, encoding="utf-8").read() if os.path.exists(cache) else ""
        self.bench_off = "SHUTTERLAB_BUILD_BENCH:BOOL=OFF" in text

    def help(self, words):
        """(options, subcommands) that `shutterlab WORDS --help` lists; None if it fails."""
        key = tuple(words)
        if key not in self.helps:
            for attempt in range(3):  # the binary may be relinking for a few seconds
                try:
                    p = subprocess.run([self.binary, *words, "--help"], capture_output=True,
                                       text=True, timeout=60)
                except OSError:
                    p = None
                if p is not None and p.returncode == 0:
                    break
                time.sleep(10 * (attempt < 2))
            if p is None or p.returncode != 0:
                self.helps[key] = None
            else:
                options, subcommands, section = set(), set(), ""
                for text in p.stdout.split("\n"):
                    if re.match(r"^\S.*:$", text):
                        section = text
                    m = re.match(r"^ {2}(-\S+)", text)  # CLI11 indents names by 2
                    if m:
                        for name in m.group(1).split(","):
                            options.add(re.sub(r"[{=].*", "", name))
                    m = re.match(r"^ {2}([a-z][\w-]*)\s", text)
                    if section.startswith("Subcommands") and m:
                        subcommands.add(m.group(1))
                self.helps[key] = (options, subcommands)
        return self.helps[key]

    def built(self, name):
        return os.path.exists(os.path.join(self.build, "bin", name[len("build/bin/"):]))

    def exists(self, name):
        """True when scripts/X is in the repository, build/bin/X in the build folder (or X is a
        benchmark that this build leaves out)."""
        if name.startswith("scripts/"):
            return os.path.exists(os.path.join(self.root, name))
        program = name[len("build/bin/"):]
        bench = os.path.join(self.root, "bench", program + ".cc")
        return self.built(name) or (self.bench_off and os.path.exists(bench))

    def check(self, where, command):
        """Findings for one command line (its comment already removed), or a synopsis: [--a X],
        A|B and --a | --b are alternatives, not pipes; a capitalised subcommand is a placeholder."""
        findings = []
        synopsis = re.sub(r"(?<=\S)\|(?=\S)|\|(?=\s*-)", " ", command).replace("[", " ")
        for name in NAMED.findall(command):
            if not self.exists(name):
                place = "the build folder" if name.startswith("build/") else "the repository"
                findings.append(f"{where}: {name} is not in {place}: {command}")
        for m in SHUTTERLAB.finditer(synopsis):
            words = m.group(1).replace("]", " ").split()
            if words and re.fullmatch(r"[A-Z][A-Z0-9_]*", words[0]):
                continue
            path, i = [], 0
            while self.help(path) and i < len(words) and words[i] in self.help(path)[1]:
                path.append(words[i])
                i += 1
            if self.help(path) is None:
                findings.append(f"{where}: shutterlab {' '.join(path)} --help fails: {command}")
                continue
            if path == [] and words and not words[0].startswith("-"):
                findings.append(f"{where}: shutterlab has no subcommand '{words[0]}': {command}")
                continue
            options = self.help(path)[0]
            for word in words[i:]:
                if word == "--":
                    break
                name = word.split("=")[0]
                if re.match(r"^--\w", name) and name not in options:
                    findings.append(f"{where}: shutterlab {' '.join(path)} has no option {name} "
                                    f"(not in its --help): {command}")
        return findings


def tail(text):
    lines = [t.strip() for t in text.strip().split("\n") if t.strip()]
    return " | ".join(lines[-STDERR_LINES:]) if lines else "(no stderr)"


def short(command, width=160):
    return command if len(command) <= width else command[:width - 3] + "..."


def script_of(block, folder, data):
    """The block as a bash script: /tmp/ and ../shared/data rewritten, exit-code lines checked.
    Line k of the block is line len(HEADER) + k of the script."""
    out = list(HEADER)
    for first, last, command in block.commands():
        text = [block.lines[n - block.line - 1] for n in range(first, last + 1)]
        m = EXIT_CODE.search(command)
        if m:
            run = command[:m.start()]
            text = [f"if {run}; then __s=0; else __s=$?; fi; __expect {m.group(1)} $__s $LINENO"]
            text += [""] * (last - first)
        for t in text:
            out.append(SHARED.sub(data, TMP.sub(folder + "/", t)))
    return "\n".join(out) + "\n"


def run_block(block, folder, cwd, data, timeout):
    """(seconds, finding or None, skipped: the finding is a command's exit SKIP)."""
    status_file = os.path.join(folder, ".doc-test-status")
    if os.path.exists(status_file):
        os.remove(status_file)
    env = dict(os.environ, SHUTTERLAB_DATA_DIR=data, data=data, DOC_TEST_STATUS=status_file)
    start = time.monotonic()
    proc = subprocess.Popen(["bash", "-c", script_of(block, folder, data)], cwd=cwd, env=env,
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        _, stderr = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        _, stderr = proc.communicate()
        seconds = time.monotonic() - start
        return seconds, (f"{block.path}:{block.line}: timed out after {timeout} s: "
                         f"{tail(stderr)}"), False
    seconds = time.monotonic() - start
    if proc.returncode == 0:
        return seconds, None, False
    line, status, expected = block.line, proc.returncode, "-"
    if os.path.exists(status_file):
        fields = open(status_file, encoding="utf-8").read().split()
        if len(fields) == 3:
            line = block.line + int(fields[0]) - len(HEADER)
            status, expected = int(fields[1]), fields[2]
    command = next((c for first, last, c in block.commands() if first <= line <= last),
                   " ".join(block.lines))
    says = f"exit code {status}" + (f" (expected {expected})" if expected != "-" else "")
    command = COMMENT.sub("", command).strip()
    if status == SKIP and expected == "-":  # the block ends here: a tool it needs is missing
        return seconds, (f"{block.path}:{line}: {short(command)}: exit code {SKIP}, a tool it "
                         f"needs is missing: {tail(stderr)}"), True
    return seconds, f"{block.path}:{line}: {short(command)}: {says}: {tail(stderr)}", False


def farm(root, build, folder):
    """A folder that stands for the repository root: a link to each entry, build to the build."""
    os.makedirs(folder)
    for name in os.listdir(root):
        os.symlink(os.path.join(root, name), os.path.join(folder, name))
    if os.path.lexists(os.path.join(folder, "build")):
        os.remove(os.path.join(folder, "build"))
    os.symlink(build, os.path.join(folder, "build"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("files", nargs="*")
    parser.add_argument("--root", default=ROOT)
    parser.add_argument("--build")
    parser.add_argument("--long", action="store_true")
    parser.add_argument("--verbose", action="store_true")
    parser.add_argument("--keep", action="store_true")
    parser.add_argument("--timeout", type=int, default=600, help="seconds a block may run")
    args = parser.parse_args()
    root = os.path.abspath(args.root)
    build = os.path.abspath(args.build or os.path.join(root, "build"))
    files = args.files or ["README.md"] + sorted(
        os.path.relpath(f, root) for f in glob.glob(os.path.join(root, "docs", "*.md")))
    data = os.environ.get("SHUTTERLAB_DATA_DIR") or os.path.join(root, "..", "shared", "data")
    data = os.path.abspath(data)

    findings, blocks_of, saved_of = [], {}, {}
    checker = Checker(root, build)
    for path in files:
        blocks, saved, spans, found = read_markdown(root, path)
        findings += found
        blocks_of[path], saved_of[path] = blocks, saved
        for line, span in spans:
            findings += checker.check(f"{path}:{line}", span)
        for block in blocks:
            written = {}
            for first, _, command in block.commands():
                if not command.lstrip().startswith("#"):
                    written[first] = checker.check(f"{path}:{first}", COMMENT.sub("", command))
                    findings += written[first]
            # What the smaller commands add: a finding the written command at that line has not.
            said = {f.rsplit(": ", 1)[0] for found in written.values() for f in found}
            for first, _, command in block.resized().commands() if block.smaller else []:
                if not command.lstrip().startswith("#"):
                    findings += [f"{f} (as the suite runs it)" for f in
                                 checker.check(f"{path}:{first}", COMMENT.sub("", command))
                                 if f.rsplit(": ", 1)[0] not in said]

    have_data = os.path.isdir(data)
    run_any = False
    temp = tempfile.mkdtemp(prefix="doc_commands.")
    try:
        for path in files:
            if not have_data:
                break
            folder = os.path.join(temp, re.sub(r"\W", "_", path))
            cwd = os.path.join(folder, "root")
            farm(root, build, cwd)
            os.makedirs(os.path.join(folder, "tmp"))
            for name, text in saved_of[path].items():  # before any block runs
                name = os.path.join(cwd, TMP.sub(os.path.join(folder, "tmp") + "/", name))
                os.makedirs(os.path.dirname(name), exist_ok=True)
                with open(name, "w", encoding="utf-8") as f:
                    f.write(text)
            after_unbuilt = None  # the block skipped for want of a benchmark: the rest follow it
            for block in blocks_of[path]:
                smaller = block.mark == "long" and not args.long
                if smaller:
                    block = block.resized()
                commands = [COMMENT.sub("", c) for _, _, c in block.commands()]
                unbuilt = [n for c in commands for n in NAMED.findall(c)
                           if n.startswith("build/") and not checker.built(n)]
                marked = block.mark is not None and block.mark != "long"
                why = ("it installs, builds or runs the tests"
                       if any(NEVER_RUN.search(c) for c in commands)
                       else f"marked {block.mark}" if marked
                       else f"{unbuilt[0]} is not built here" if unbuilt
                       else f"it may read what line {after_unbuilt} wrote, which did not run"
                       if after_unbuilt else None)
                if unbuilt and not after_unbuilt:
                    after_unbuilt = block.line
                if why:
                    if args.verbose:
                        print(f"{block.path}:{block.line}: not run ({why})")
                    continue
                run_any = True
                seconds, finding, skipped = run_block(block, os.path.join(folder, "tmp"), cwd,
                                                      data, args.timeout)
                if skipped and os.environ.get("CI") != "true":
                    print(finding)
                    finding = None
                elif skipped:
                    finding += " (CI=true needs it)"
                if finding and smaller:
                    finding += " (as the suite runs it)"
                if args.verbose:
                    mark = ("" if block.mark != "long" else " (long)" if args.long
                            else " (long, run smaller)")
                    outcome = ("  FAILED" if finding else "  SKIPPED" if skipped else "")
                    print(f"{block.path}:{block.line}: {seconds:6.1f} s{mark}{outcome}", flush=True)
                if finding:
                    findings.append(finding)
    finally:
        if args.keep:
            print(f"outputs kept in {temp}")
        else:
            shutil.rmtree(temp, ignore_errors=True)

    def place(finding):  # the files' order, then the line
        path, line = finding.split(":")[:2]
        return files.index(path) if path in files else len(files), int(line)

    for finding in sorted(findings, key=place):
        print(finding)
    if findings:
        return 1
    if not have_data:
        if os.environ.get("CI") == "true":
            print(f"the shared data folder {data} is missing (CI=true needs it)")
            return 1
        print(f"the shared data folder {data} is absent (set SHUTTERLAB_DATA_DIR or put "
              f"../shared/data beside the checkout): the commands were checked, not run")
        return SKIP
    if args.verbose and not run_any:
        print("no block ran")
    return 0


if __name__ == "__main__":
    sys.exit(main())
