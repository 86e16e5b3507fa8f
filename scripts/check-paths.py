#!/usr/bin/env python3
"""Checks that the repository's text points at files that exist.

Usage: scripts/check-paths.py [--layout] [ROOT]        (ROOT: the repository, default: this one)

Without --layout: every repository path cited in a comment of a *.cpp, *.hpp, *.inc, *.cmake,
CMakeLists.txt, *.sh or *.py file, and anywhere in a Markdown file (text, code blocks and
relative links), must name a file or folder of the tree, and a Markdown link's #anchor must name
a heading of the file it points to. Each missing one is printed as
FILE:LINE: PATH and the exit code is 1.

What counts as a repository path (the allow rule for generated and user paths):
  - a path whose first component is a top-level folder of the tree (`tests/cli/test_cli.cpp`,
    `docs/design.md`, `experiments/`); anything else is not checked, so build folders
    (`build/`, `build-sanitize/`), output folders (`results/`, a user's `OUT/`, `DIR/`) and
    absolute paths are left alone;
  - and that is not the tail of a longer path (`build/experiments/stiffbench`,
    `BUILD/tests/...` and `$root/scripts/...` are relative to something else);
  - `../` prefixes and Markdown links are resolved from the citing file's folder.
A cited path matches when some file or folder of the tree has it. Placeholders match anything:
a word in capitals (`NAME`, `TARGET`, `X`; tried only when the literal path is missing), `<...>`,
`*`, `…`/`...`; `{a,b}` means both a and b; a trailing `:LINE` is ignored; a path without an
extension also matches its files with one (`core/linear_stability` = its .hpp and .cpp).

With --layout: the "## Layout" block of docs/README.md must list every folder of the tree at
depth one and two (one line each, written `name/` at the start of a line, or `  sub/` indented
under its parent) and no folder that does not exist.

The tree is `git ls-files` (tracked and untracked-but-not-ignored files) when ROOT is a git
checkout, otherwise every file under ROOT outside build*/, results*/ and hidden folders.
"""
import fnmatch
import os
import re
import subprocess
import sys

CPP_EXT = (".cpp", ".hpp", ".inc", ".h", ".c")
HASH_EXT = (".cmake", ".sh", ".py")


def tree_files(root):
    try:
        out = subprocess.run(
            ["git", "-C", root, "ls-files", "--cached", "--others", "--exclude-standard"],
            check=True, capture_output=True, text=True).stdout
        files = [f for f in out.splitlines() if os.path.exists(os.path.join(root, f))]
        if files:
            return sorted(set(files))
    except (OSError, subprocess.CalledProcessError):
        pass
    files = []
    for d, dirs, names in os.walk(root):
        rel = os.path.relpath(d, root)
        dirs[:] = [x for x in dirs if not (x.startswith(".") and x != ".ci")
                   and not x.startswith("build") and not x.startswith("results")]
        for n in names:
            files.append(os.path.normpath(os.path.join(rel, n)))
    return sorted(files)


def folders_of(files):
    dirs = set()
    for f in files:
        parts = f.split("/")[:-1]
        for i in range(1, len(parts) + 1):
            dirs.add("/".join(parts[:i]))
    return dirs


# ---- Comments --------------------------------------------------------------------------------

def cpp_comments(text):
    """(line, text) of every // and /* */ comment, skipping string and character literals."""
    out, i, n, line = [], 0, len(text), 1
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            i += 1
        elif text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append((line, text[i:j]))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            for k, part in enumerate(text[i:j].split("\n")):
                out.append((line + k, part))
            line += text.count("\n", i, j)
            i = j
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not text[i - 1].isalnum()):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                i += 1
                continue
            end = text.find(")" + m.group(1) + '"', i)
            end = n if end < 0 else end + len(m.group(1)) + 2
            line += text.count("\n", i, end)
            i = end
        elif c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            i = j + 1
        else:
            i += 1
    return out


def hash_comments(text, python):
    """(line, text) of # comments (and Python triple-quoted strings)."""
    out = []
    if python:
        for m in re.finditer(r'"""(.*?)"""', text, re.S):
            first = text.count("\n", 0, m.start()) + 1
            for k, part in enumerate(m.group(1).split("\n")):
                out.append((first + k, part))
    for no, line in enumerate(text.split("\n"), 1):
        quote = None
        for k, c in enumerate(line):
            if quote:
                if c == quote:
                    quote = None
                elif c == "\\":
                    continue
            elif c in "'\"":
                quote = c
            elif c == "#" and (k == 0 or line[k - 1] in " \t"):
                out.append((no, line[k:]))
                break
    return out


def cited_text(path, text):
    name = os.path.basename(path)
    if name.endswith(CPP_EXT):
        return cpp_comments(text)
    if name == "CMakeLists.txt" or name.endswith(HASH_EXT):
        return hash_comments(text, name.endswith(".py"))
    if name.endswith(".md"):
        return list(enumerate(text.split("\n"), 1))
    return []


# ---- Paths -----------------------------------------------------------------------------------

def expand_braces(p):
    m = re.search(r"\{([^{}]*)\}", p)
    if not m:
        return [p]
    return [x for alt in m.group(1).split(",")
            for x in expand_braces(p[:m.start()] + alt + p[m.end():])]


def as_pattern(p, placeholders):
    p = re.sub(r"<[^>]*>", "*", p)
    p = p.replace("…", "*").replace("...", "*")
    if placeholders:
        p = re.sub(r"(?<![A-Za-z])[A-Z][A-Z0-9_]*(?![a-z])", "*", p)
    return re.sub(r"\*+", "*", p)


class Tree:
    def __init__(self, files):
        self.files = set(files)
        self.dirs = folders_of(files)
        self.entries = sorted(self.files | {d + "/" for d in self.dirs})

    def has(self, path):
        want_dir = path.endswith("/")
        path = path.rstrip("/")
        if not path:
            return True
        for placeholders in (False, True):
            pat = as_pattern(path, placeholders)
            if "*" not in pat and "?" not in pat:
                if path in self.dirs or (not want_dir and path in self.files):
                    return True
                continue
            if any(fnmatch.fnmatchcase(e.rstrip("/"), pat) or
                   fnmatch.fnmatchcase(e, pat + "/*") for e in self.entries):
                return True
        if not want_dir and "." not in os.path.basename(path):
            stem = as_pattern(path, False) + ".*"
            return any(fnmatch.fnmatchcase(f, stem) for f in self.files)
        return False


def path_regex(tops):
    names = "|".join(sorted((re.escape(t) for t in tops), key=len, reverse=True))
    return re.compile(r"(?<![\w.~$/@:-])((?:\.\./)*)((?:%s)/(?:[\w.\-/*<>…+]|\{[^}\s]*\})*)"
                      % names)


LINK = re.compile(r"\]\(([^)\s]+)\)")


def heading_anchors(path, cache={}):
    """GitHub's anchors of a Markdown file's headings (outside code blocks)."""
    if path not in cache:
        anchors, fenced = set(), False
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("```"):
                    fenced = not fenced
                m = None if fenced else re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
                if m:
                    anchors.add(re.sub(r"[^\w\- ]", "", m.group(1).lower()).replace(" ", "-"))
        cache[path] = anchors
    return cache[path]


def resolve(base_dir, prefix, rel):
    p = os.path.normpath(os.path.join(base_dir, prefix + rel)) if prefix else rel
    if p.startswith(".."):
        return None
    return p + ("/" if rel.endswith("/") and not p.endswith("/") else "")


def check_paths(root, files):
    tree = Tree(files)
    tops = {f.split("/")[0] for f in files if "/" in f}
    rx = path_regex(tops)
    missing = []
    for f in files:
        name = os.path.basename(f)
        if not (name.endswith(CPP_EXT + HASH_EXT + (".md",)) or name == "CMakeLists.txt"):
            continue
        try:
            with open(os.path.join(root, f), encoding="utf-8") as fh:
                text = fh.read()
        except (OSError, UnicodeDecodeError):
            continue
        base = os.path.dirname(f)
        for line, chunk in cited_text(f, text):
            cited = []
            for m in rx.finditer(chunk):
                raw = m.group(2).rstrip(".-")
                cited.append((m.group(0).rstrip(".-"), resolve(base, m.group(1), raw)))
            if f.endswith(".md"):
                for m in LINK.finditer(chunk):
                    target, _, anchor = m.group(1).partition("#")
                    if re.match(r"[a-z]+:", target) or target.startswith("/"):
                        continue
                    p = resolve(base, "./", target) if target else f
                    if target:
                        cited.append((target, p))
                    if anchor and p and p.endswith(".md") and p in tree.files and \
                            anchor not in heading_anchors(os.path.join(root, p)):
                        missing.append("%s:%d: %s (no such heading)" % (f, line, m.group(1)))
            for shown, p in cited:
                if p is None:
                    continue
                if not any(tree.has(x) for x in expand_braces(p)):
                    missing.append("%s:%d: %s" % (f, line, shown))
    return missing


# ---- Layout ----------------------------------------------------------------------------------

def check_layout(root, files):
    with open(os.path.join(root, "docs", "README.md"), encoding="utf-8") as fh:
        text = fh.read()
    m = re.search(r"^## Layout\s*\n.*?```[^\n]*\n(.*?)```", text, re.S | re.M)
    if not m:
        return ["docs/README.md: no ## Layout section with a code block"]
    listed, parent = [], None
    for line in m.group(1).split("\n"):
        top = re.match(r"([\w.-]+)/(\s|$)", line)
        sub = re.match(r"\s+([\w.-]+)/(\s|$)", line)
        if top:
            parent = top.group(1)
            listed.append(parent)
        elif sub and parent:
            listed.append(parent + "/" + sub.group(1))
    actual = {d for d in folders_of(files) if d.count("/") <= 1}
    problems = ["docs/README.md Layout: folder %s/ is not listed" % d
                for d in sorted(actual - set(listed))]
    problems += ["docs/README.md Layout: %s/ is listed but does not exist" % d
                 for d in sorted(set(listed) - actual)]
    problems += ["docs/README.md Layout: %s/ is listed twice" % d
                 for d in sorted({d for d in listed if listed.count(d) > 1})]
    return problems


def main(argv):
    layout = "--layout" in argv
    args = [a for a in argv if a != "--layout"]
    root = os.path.abspath(args[0] if args else os.path.join(os.path.dirname(__file__), ".."))
    files = tree_files(root)
    problems = check_layout(root, files) if layout else check_paths(root, files)
    for p in problems:
        print(p)
    if problems:
        what = "layout problem(s)" if layout else "cited path(s) that do not exist"
        print("%d %s" % (len(problems), what), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
