#!/usr/bin/env python3
"""The layout's own rules, checked against the code (ctest runs each check as layout.CHECK).

  links       every #include of a project library or a third-party package is linked by the
              including file's target (build/layout.txt, written by CMakeLists.txt); a library
              links exactly what its files include, PUBLIC when one of its headers includes it,
              PRIVATE otherwise; the libraries' link graph has no circle
  unit-loops  no two units (name.h + name.cc) of one folder include each other's header, directly
              or round a longer circle
  functions   no function (lambdas included) longer than 100 lines in the code (not the tests),
              measured by Universal Ctags
  paths       every repository path named in a tracked file (a comment, a doc, a script) exists
  tests       each test file sits in the mirror of the library it tests: tests/FOLDER/ for a
              FOLDER that is a library (or app/, scripts/), and a file named after a unit
              (UNIT_test.cc) beside that unit's own folder
  readme      the "Layout" block of docs/development.md (the README links it) names every folder
              that holds code, each library with its target, and no folder that does not exist;
              the README stays under 150 lines

Usage: scripts/check_layout.py CHECK [--build DIR]      (stdlib only; run from anywhere)
Exit 0 when the check holds, 1 with one line per finding (FILE:LINE: problem) when it does not,
2 on bad usage.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CODE_FOLDERS = ("sim", "record", "model", "io", "render", "estimate", "app", "bench", "fuzz")
MAX_FUNCTION_LINES = 100

# Third-party headers by prefix and the link target that provides them. Headers of the C and C++
# standard libraries and of the system (unistd.h, sys/, linux/, immintrin.h) need no link.
THIRD_PARTY = [
    ("Eigen/", "Eigen3::Eigen"),
    ("opencv2/core", "opencv_core"),
    ("opencv2/imgproc", "opencv_imgproc"),
    ("opencv2/imgcodecs", "opencv_imgcodecs"),
    ("opencv2/videoio", "opencv_videoio"),
    ("opencv2/video/", "opencv_video"),
    ("opencv2/calib3d", "opencv_calib3d"),
    ("nlohmann/", "nlohmann_json::nlohmann_json"),
    ("OpenImageIO/", "OpenImageIO::OpenImageIO"),
    ("exiv2/", "exiv2lib"),
    ("gpiod.h", "PkgConfig::GPIOD"),
    ("toml++/", "PkgConfig::TOMLPP"),
    ("xxhash.h", "PkgConfig::XXHASH"),
    ("jpeglib.h", "JPEG::JPEG"),
    ("png.h", "PNG::PNG"),
    ("CLI/", "CLI11::CLI11"),
    ("benchmark/", "benchmark::benchmark"),
    ("gtest/", "GTest::gtest"),
    ("gmock/", "GTest::gmock"),
    ("thread", "Threads::Threads"),  # <thread> exactly: std::thread needs the threads library
]

INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')


def read_lines(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        return f.read().split("\n")


def includes_of(path):
    """[(line number, header, quoted)] of one file."""
    out = []
    for number, line in enumerate(read_lines(path), 1):
        m = INCLUDE.match(line)
        if m:
            out.append((number, m.group(2), m.group(1) == '"'))
    return out


def third_party_target(header):
    for prefix, target in THIRD_PARTY:
        if prefix == "thread":
            if header == "thread":
                return target
        elif header.startswith(prefix):
            return target
    return None


class Layout:
    """build/layout.txt: target|sources|public,links|private,links."""

    def __init__(self, path):
        self.public, self.private, self.sources = {}, {}, {}
        self.folder_target = {}  # a library's folder -> its target
        self.tested = {}  # tests/FOLDER -> the library a test folder tests (its first link)
        for number, line in enumerate(read_lines(path), 1):
            if not line.strip():
                continue
            parts = line.split("|")
            if len(parts) != 4:
                sys.exit(f"{path}:{number}: expected target|sources|public|private, got '{line}'")
            target, sources, public, private = parts
            self.sources[target] = [s for s in sources.split(",") if s]
            self.public[target] = [s for s in public.split(",") if s]
            self.private[target] = [s for s in private.split(",") if s]
            folder = self.sources[target][0] if len(self.sources[target]) == 1 else ""
            if folder and os.path.isdir(os.path.join(ROOT, folder)):
                if folder.startswith("tests/"):
                    self.tested[folder] = (self.public[target] + self.private[target])[0]
                else:
                    self.folder_target[folder] = target

    def is_library(self, target):
        return any(self.folder_target.get(f) == target for f in self.sources[target]) and \
            not self.sources[target][0].startswith(("app", "tests/"))

    def closure(self, target):
        """What target may include: itself, its direct links, and their PUBLIC links, on down."""
        seen = {target}
        stack = list(self.public.get(target, [])) + list(self.private.get(target, []))
        while stack:
            t = stack.pop()
            if t in seen:
                continue
            seen.add(t)
            stack.extend(self.public.get(t, []))
        return seen

    def header_target(self, header):
        """The target a quoted project header belongs to; None for a header of no target."""
        folder = os.path.dirname(header)
        if folder in self.folder_target:
            return self.folder_target[folder]
        if folder in self.tested:  # a test folder's fixtures: the library it tests
            return self.tested[folder]
        return None


def files_of_target(layout, target):
    """(file, [folders whose headers are this target's own])."""
    files, folders = [], []
    for source in layout.sources[target]:
        path = os.path.join(ROOT, source)
        if os.path.isdir(path):
            folders.append(source)
            files += [os.path.join(source, n) for n in sorted(os.listdir(path))
                      if n.endswith((".h", ".cc"))]
        else:
            files.append(source)
            folders.append(os.path.dirname(source))
    return files, folders


def check_links(build):
    layout_path = os.path.join(build, "layout.txt")
    if not os.path.isfile(layout_path):
        print(f"{layout_path}: not found: configure the build first (scripts/setup.sh)")
        return 1
    layout = Layout(layout_path)
    findings = []
    for target in layout.sources:
        allowed = layout.closure(target)
        files, own_folders = files_of_target(layout, target)
        own_headers = set()
        used_public, used_private = set(), set()
        queue, visited = list(files), set()
        while queue:
            rel = queue.pop(0)
            if rel in visited:
                continue
            visited.add(rel)
            in_header = rel.endswith(".h")
            for number, header, quoted in includes_of(os.path.join(ROOT, rel)):
                needed = None
                if quoted and not os.path.exists(os.path.join(ROOT, header)):
                    findings.append(f"{rel}:{number}: includes {header}, which does not exist")
                    continue
                if quoted:
                    folder = os.path.dirname(header)
                    if folder in own_folders or (folder == "tests" and target.endswith("_tests")):
                        queue.append(header)  # the target's own header: read it as its own
                        own_headers.add(header)
                        continue
                    needed = layout.header_target(header)
                    if needed is None:
                        continue
                    if folder.startswith("tests/"):
                        queue.append(header)  # a fixture of a lower test folder: its includes too
                else:
                    needed = third_party_target(header)
                if needed is None or needed == target:
                    continue
                shown = f'"{header}"' if quoted else f"<{header}>"
                (used_public if in_header else used_private).add(needed)
                if needed not in allowed:
                    findings.append(
                        f"{rel}:{number}: includes {shown} of {needed}, which {target} does not "
                        f"link (add it to {target}'s link line in CMakeLists.txt)")
        if layout.is_library(target):
            # A library's link line is exactly what its files include.
            linked_public, linked_private = set(layout.public[target]), set(layout.private[target])
            for dep in sorted(used_public):
                if dep in linked_private:
                    findings.append(f"CMakeLists.txt: {target} links {dep} PRIVATE, but a header "
                                    f"of it includes {dep}: make it PUBLIC")
                elif dep not in linked_public:
                    findings.append(f"CMakeLists.txt: {target}'s headers include {dep}: link it "
                                    f"PUBLIC")
            for dep in sorted(used_private - used_public):
                if dep not in linked_public | linked_private:
                    findings.append(f"CMakeLists.txt: {target}'s files include {dep}: link it "
                                    f"PRIVATE")
                elif dep in linked_public:
                    findings.append(f"CMakeLists.txt: {target} links {dep} PUBLIC, but only its "
                                    f".cc files include it: make it PRIVATE")
            for dep in sorted((linked_public | linked_private) - used_public - used_private):
                findings.append(f"CMakeLists.txt: {target} links {dep}, which none of its files "
                                f"includes: drop it")
    # The libraries' link graph: one way, no circle.
    def visit(target, path, state):
        state[target] = 1
        for dep in layout.public.get(target, []) + layout.private.get(target, []):
            if state.get(dep) == 1:
                findings.append("CMakeLists.txt: the links run in a circle: " +
                                " -> ".join(path[path.index(dep):] + [dep]))
            elif dep in layout.sources and state.get(dep) is None:
                visit(dep, path + [dep], state)
        state[target] = 2
    state = {}
    for target in layout.sources:
        if state.get(target) is None:
            visit(target, [target], state)
    return report(findings)


def tracked_files():
    out = subprocess.run(["git", "-C", ROOT, "ls-files", "-z"], capture_output=True, check=True)
    return [f for f in out.stdout.decode().split("\0") if f]


def code_files():
    return [f for f in tracked_files()
            if f.endswith((".h", ".cc")) and f.split("/")[0] in CODE_FOLDERS]


def check_unit_loops():
    findings = []
    by_folder = {}
    for f in code_files() + [f for f in tracked_files() if f.startswith("tests/") and f.endswith((".h", ".cc"))]:
        by_folder.setdefault(os.path.dirname(f), []).append(f)
    for folder, files in sorted(by_folder.items()):
        unit_of = lambda path: os.path.splitext(os.path.basename(path))[0]
        units = {unit_of(f) for f in files}
        edges = {}
        where = {}
        for f in files:
            for number, header, quoted in includes_of(os.path.join(ROOT, f)):
                if quoted and os.path.dirname(header) == folder and unit_of(header) in units \
                        and unit_of(header) != unit_of(f):
                    edges.setdefault(unit_of(f), set()).add(unit_of(header))
                    where.setdefault((unit_of(f), unit_of(header)), f"{f}:{number}")
        # Tarjan's strongly connected components: a component of two or more units is a circle.
        index, low, stack, on_stack, counter = {}, {}, [], set(), [0]
        def connect(v):
            index[v] = low[v] = counter[0]
            counter[0] += 1
            stack.append(v)
            on_stack.add(v)
            for w in sorted(edges.get(v, ())):
                if w not in index:
                    connect(w)
                    low[v] = min(low[v], low[w])
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
            if low[v] == index[v]:
                component = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    component.append(w)
                    if w == v:
                        break
                if len(component) > 1:
                    component.sort()
                    links = [where[(a, b)] for a in component for b in component
                             if (a, b) in where]
                    findings.append(f"{folder}: units include each other's headers in a circle: "
                                    f"{', '.join(component)} ({'; '.join(links)})")
        for v in sorted(units):
            if v not in index:
                connect(v)
    return report(findings)


def check_functions():
    ctags = shutil.which("ctags-universal") or shutil.which("ctags")
    if ctags is None:
        print("ctags not found: install universal-ctags (scripts/test.sh does)")
        return 1
    out = subprocess.run(
        [ctags, "--languages=C++", "--kinds-C++=f", "--fields=+ne", "-x",
         "--_xformat=%{line} %{end} %F %N"] + code_files(),
        cwd=ROOT, capture_output=True, text=True)
    if out.returncode != 0 or "Universal Ctags" not in subprocess.run(
            [ctags, "--version"], capture_output=True, text=True).stdout:
        print(f"{ctags}: not Universal Ctags, or it failed: {out.stderr.strip()}")
        return 1
    findings = []
    for row in out.stdout.splitlines():
        parts = row.split(" ", 3)
        if len(parts) < 4 or not parts[1].isdigit():
            continue
        begin, end, path, name = int(parts[0]), int(parts[1]), parts[2], parts[3]
        lines = end - begin + 1
        if lines > MAX_FUNCTION_LINES:
            name = "a lambda" if name.startswith("__anon") else name
            findings.append(f"{path}:{begin}: {name} is {lines} lines (at most "
                            f"{MAX_FUNCTION_LINES}: split it)")
    return report(sorted(findings))


PATH_IN_TEXT = re.compile(
    r"(?<![\w./-])((?:sim|record|model|io|render|estimate|app|tests|scripts|docs|bench|fuzz|assets|"
    r"third_party|\.ci)/[A-Za-z0-9_/.-]*[A-Za-z0-9_])")
PATH_SUFFIXES = (".h", ".cc", ".md", ".sh", ".py", ".txt", ".json", ".csv", ".png", ".js", ".css")


def commented_text(path, line):
    """What of one line a reader takes as prose: a C++ file's // comment, a script's # comment
    (CMake, shell, Python), a document's whole line."""
    if path.endswith((".md", ".txt")):
        return line
    marker = "//" if path.endswith((".h", ".cc")) else "#"
    at = line.find(marker)
    return line[at:] if at >= 0 else ""


# A placeholder (fuzz/NAME_fuzz.cc, tests/FOLDER/UNIT_test.cc) names no file.
PLACEHOLDER = re.compile(r"(?<![A-Za-z])(NAME|FOLDER|UNIT|TARGET|LIBRARY_FOLDER|LIBRARY|DIR|FILE|"
                         r"PATH|COMMIT|N|X)(?![a-z])")


def check_paths():
    findings = []
    files = tracked_files()
    existing = set(files)
    for f in files:
        prose = f.endswith((".h", ".cc", ".md", ".sh", ".py", ".txt")) or f.startswith(".ci/")
        # tests/scripts/ name the files of the throwaway repositories they make.
        if not prose or f.startswith(("third_party/", "tests/scripts/")):
            continue
        for number, line in enumerate(read_lines(os.path.join(ROOT, f)), 1):
            for m in PATH_IN_TEXT.finditer(commented_text(f, line)):
                path = m.group(1).rstrip(".")
                if PLACEHOLDER.search(path):
                    continue
                # A file (a path with a file's suffix), or a folder or unit of the code without one
                # (sim/logs, estimate/paper/flight). "record/1" and "io/" read as words are not
                # taken for paths: a one-level path under them is not checked.
                if not path.endswith(PATH_SUFFIXES):
                    if "." in os.path.basename(path):
                        continue
                    if path.count("/") < 2 and path.split("/")[0] in ("record", "io"):
                        continue
                if path in existing or any(os.path.exists(os.path.join(ROOT, path + end))
                                           for end in ("", ".h", ".cc")):
                    continue
                findings.append(f"{f}:{number}: names {path}, which does not exist")
    return report(findings)


def check_tests():
    findings = []
    folders_with_code = {os.path.dirname(f) for f in code_files()}
    unit_home = {}
    for f in code_files():
        if os.path.dirname(f) not in ("app", "bench", "fuzz"):  # commands, not units
            unit_home.setdefault(os.path.splitext(os.path.basename(f))[0], set()).add(
                os.path.dirname(f))
    for f in tracked_files():
        if not f.startswith("tests/") or not f.endswith("_test.cc") and not f.endswith("_test.sh"):
            continue
        folder = os.path.dirname(f)[len("tests/"):]
        if f.endswith(".sh"):
            if folder != "scripts":
                findings.append(f"{f}: a script's test belongs in tests/scripts/")
            continue
        if folder not in folders_with_code or folder in ("bench", "fuzz"):
            findings.append(f"{f}: tests/{folder}/ mirrors no library folder: move it to "
                            f"tests/LIBRARY_FOLDER/")
            continue
        unit = os.path.basename(f)[: -len("_test.cc")]
        homes = unit_home.get(unit, set())
        if homes and folder not in homes and folder != "app":
            findings.append(f"{f}: tests the unit {unit} of {', '.join(sorted(homes))}/: move it "
                            f"to tests/{sorted(homes)[0]}/")
    return report(findings)


# The layout block the readme check compares with the tree.
LAYOUT_DOC = "docs/development.md"
README_MAX_LINES = 150


def check_readme(build):
    findings = []
    doc = LAYOUT_DOC
    lines = read_lines(os.path.join(ROOT, doc))
    try:
        start = lines.index("## Layout")
        begin = lines.index("```", start) + 1
        end = lines.index("```", begin)
    except ValueError:
        print(f"{doc}: no \"## Layout\" section with a ``` block")
        return 1
    named = {}
    for number, line in enumerate(lines[begin:end], begin + 1):
        m = re.match(r"^(\S+)/\s+(\S+)", line)
        if m:
            named[m.group(1)] = (number, m.group(2).rstrip(":"))
    for folder, (number, _) in named.items():
        if not os.path.isdir(os.path.join(ROOT, folder)):
            findings.append(f"{doc}:{number}: names {folder}/, which does not exist")
    code_folders = {os.path.dirname(f) for f in code_files()}
    for folder in sorted(code_folders):
        if folder not in named:
            findings.append(f"{doc}: the Layout block does not name {folder}/")
    layout_path = os.path.join(build, "layout.txt")
    if not os.path.isfile(layout_path):
        findings.append(f"{layout_path}: not found: configure the build first (scripts/setup.sh)")
    else:
        layout = Layout(layout_path)
        for folder, target in sorted(layout.folder_target.items()):
            if target.startswith("shutterlab_") and folder in named and named[folder][1] != target:
                findings.append(f"{doc}:{named[folder][0]}: {folder}/ is {target}, not "
                                f"{named[folder][1]}")
    for top in ("tests", "scripts", "docs", "fuzz", "bench", "third_party"):
        if os.path.isdir(os.path.join(ROOT, top)) and top not in named:
            findings.append(f"{doc}: the Layout block does not name {top}/")
    # The README is for users (issue 43): studies and histories belong in docs/.
    readme_lines = len(read_lines(os.path.join(ROOT, "README.md")))
    if readme_lines >= README_MAX_LINES:
        findings.append(f"README.md: {readme_lines} lines, fewer than {README_MAX_LINES} wanted: "
                        "move details to docs/")
    return report(findings)


def report(findings):
    for line in findings:
        print(line)
    return 1 if findings else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("check",
                        choices=["links", "unit-loops", "functions", "paths", "tests", "readme"])
    parser.add_argument("--build", default=os.path.join(ROOT, "build"),
                        help="the build folder whose layout.txt the links check reads")
    args = parser.parse_args()
    checks = {"links": lambda: check_links(args.build), "unit-loops": check_unit_loops,
              "functions": check_functions, "paths": check_paths, "tests": check_tests,
              "readme": lambda: check_readme(args.build)}
    sys.exit(checks[args.check]())


if __name__ == "__main__":
    main()
