#!/usr/bin/env python3
"""Lists functions longer than a limit (default 80 lines) in the C++ sources outside tests.

A function is a brace block at namespace or class level whose header (the text since the previous
';', '{' or '}' at that level) ends with ')' plus qualifiers: free functions, member functions,
templates and lambdas assigned at that level. Length counts the lines from the header's '{' to
its '}'. Comments and strings are blanked first, so braces inside them do not count.

    scripts/function_lengths.py [--limit N] [PATH ...]   (default: model identification
    trajectory apps python)
Exit status 1 when some function is over the limit.
"""
import argparse
import pathlib
import re
import sys

HEADER_END = re.compile(r"\)\s*(const|override|final|noexcept|mutable|->\s*[\w:<>,\s*&]+|\s)*$")
NOT_FUNCTION = re.compile(r"^\s*(namespace|struct|class|enum|union|extern)\b|=\s*$|\b(if|for|while|switch|catch)\s*\(")


def blank(text):
    """Replaces comments and string/char literals by spaces, keeping newlines."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + re.sub(r"[^\n]", " ", text[i + 1:j]) + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(path):
    text = blank(path.read_text(errors="replace"))
    stack = []  # (is_function, start_line, name)
    header_start = 0
    line = 1
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
        elif c == "{":
            header = text[header_start:i]
            inside_function = any(f for f, _, _ in stack)
            is_fn = (not inside_function and HEADER_END.search(header.strip() or "x") is not None
                     and not NOT_FUNCTION.search(header))
            name = ""
            if is_fn:
                m = re.search(r"([~\w:]+|operator\s*\S+)\s*\([^()]*(\([^()]*\)[^()]*)*\)[^()]*$", header)
                name = m.group(1) if m else header.strip().splitlines()[-1][:40]
            stack.append((is_fn, line, name))
            header_start = i + 1
        elif c == "}":
            if stack:
                is_fn, start, name = stack.pop()
                if is_fn:
                    yield name, start, line - start + 1
            header_start = i + 1
        elif c == ";" and not any(f for f, _, _ in stack):
            header_start = i + 1


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--limit", type=int, default=80)
    ap.add_argument("paths", nargs="*", default=["model", "identification", "trajectory", "apps", "python"])
    a = ap.parse_args()
    root = pathlib.Path(__file__).resolve().parent.parent
    over = []
    for p in a.paths:
        base = root / p
        files = [base] if base.is_file() else sorted(list(base.rglob("*.cc")) + list(base.rglob("*.h")))
        for f in files:
            for name, start, length in functions(f):
                if length > a.limit:
                    over.append((length, f"{f.relative_to(root)}:{start}", name))
    for length, where, name in sorted(over, reverse=True):
        print(f"{length:5d}  {where}  {name}")
    print(f"{len(over)} functions over {a.limit} lines")
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())
