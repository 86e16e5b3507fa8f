#!/usr/bin/env python3
"""The longest functions of C++ files: scripts/function_lengths.py [-n N] [--max L] FILE...

A function is a brace block opened at namespace level (outside classes: their member functions
are measured as blocks at class level) whose header contains '('; its length counts the lines
from the header's first line to the closing brace. Lambdas count toward their function. With
--max L the exit code is 1 when a function is longer than L lines.
"""
import re
import sys


def functions(path):
    text = open(path).read()
    # Blank out comments, strings and character literals (keeping newlines) so braces in them
    # do not count.
    out, i = [], 0
    while i < len(text):
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = len(text) if j < 0 else j
            out.append(" " * (j - i)); i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2); j = len(text) if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        elif text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:end])); i = end
        elif text[i] in "\"'":
            q, j = text[i], i + 1
            while j < len(text) and text[j] != q:
                j += 2 if text[j] == "\\" else 1
            out.append(" " * (j + 1 - i)); i = j + 1
        else:
            out.append(text[i]); i += 1
    code = "".join(out)
    lines = code.split("\n")
    stack = []  # (kind, start line, header)
    header_start = 0
    result = []
    for n, line in enumerate(lines):
        for ch in line:
            if ch == "{":
                # The header: text since the last ';', '{' or '}' at this level.
                prev = "\n".join(lines[header_start:n + 1])
                last = max(prev.rfind(";"), prev.rfind("}"))
                head = prev[last + 1:] if last >= 0 else prev
                outer = [k for k, _, _ in stack]
                is_func = "(" in head and not re.search(r"\b(namespace|class|struct|enum)\b", head) \
                    and all(k in ("ns", "class") for k in outer)
                kind = "func" if is_func else ("class" if re.search(r"\b(class|struct)\b", head) else
                                               ("ns" if "namespace" in head else "other"))
                # The header's first non-empty line.
                hl = head.split("\n")
                start = n - (len(hl) - 1)
                while start < n and not lines[start].strip():
                    start += 1
                stack.append((kind, start, " ".join(head.split())))
                header_start = n
            elif ch == "}":
                if stack:
                    kind, start, head = stack.pop()
                    if kind == "func":
                        result.append((n - start + 1, start + 1, head))
                header_start = n
    return result


def main(argv):
    n, limit, files = 5, None, []
    it = iter(argv[1:])
    for a in it:
        if a == "-n":
            n = int(next(it))
        elif a == "--max":
            limit = int(next(it))
        else:
            files.append(a)
    all_f = []
    for f in files:
        for length, line, head in functions(f):
            name = re.sub(r"\s*\(.*", "", head).split()[-1] if head else "?"
            all_f.append((length, f"{f}:{line}", name))
    all_f.sort(reverse=True)
    for length, where, name in all_f[:n]:
        print(f"{length:5d}  {where}  {name}")
    if limit is not None and all_f and all_f[0][0] > limit:
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
