#!/usr/bin/env python3
"""The brief's size limits: no function over 200 lines, no source file over 900 lines, in cli/, formats/,
pipeline/, anatomy/, sample/, runtime/ and app/.

Usage: scripts/check-sizes.py [--record]
Code written before the limits held is listed in tests/data/size-limits-known.txt with its length at
the time: such a file or function may shrink, not grow, and a new one over a limit fails. --record
rewrites the list (after splitting something, to lower the recorded lengths; never to let new code in).

A function is a brace block opened at namespace or class level after a closing parenthesis (with
const, noexcept, override, a trailing return type or a constructor's initializer list in between);
lambdas and blocks inside it count as its lines. Comments and strings are blanked before braces are
matched, so a brace in either cannot confuse the count.
"""
import os
import re
import sys

import cpp_lex

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DIRS = ["cli", "formats", "pipeline", "anatomy", "sample", "runtime", "app"]
FILE_LIMIT = 900
FUNCTION_LIMIT = 200
KNOWN = os.path.join(REPO, "tests", "data", "size-limits-known.txt")
CONTROL = {"if", "for", "while", "switch", "catch", "return", "sizeof", "decltype", "alignof", "static_assert"}


def blank_comments_and_strings(text):
    """Replaces comments and string/char literals with spaces, keeping newlines (line numbers)."""
    out, done = [], 0
    for _, start, end, _, _ in cpp_lex.spans(text):
        out.append(text[done:start])
        out.append(re.sub(r"[^\n]", " ", text[start:end]))
        done = end
    out.append(text[done:])
    return "".join(out)


def functions(text):
    """(name, first line, line count) of every function body at namespace or class level."""
    code = blank_comments_and_strings(text)
    # Preprocessor lines hold no function bodies and may hold unbalanced text.
    code = re.sub(r"(?m)^[ \t]*#.*$", lambda m: " " * len(m.group(0)), code)
    found = []
    stack = []  # per open brace: ("function", name, first line) or ("block", None, 0)
    segment_start = 0
    for i, c in enumerate(code):
        if c == "{":
            inside_function = any(kind == "function" for kind, _, _ in stack)
            entry = ("block", None, 0)
            if not inside_function:
                flat = " ".join(code[segment_start:i].split())
                # A function head ends with ')' then qualifiers, a trailing return type or a constructor's
                # initializer list.
                sig = re.search(r"([~\w:<>]+)\s*\((?:[^()]|\([^()]*\))*\)\s*"
                                r"(?:const|noexcept|override|final|mutable|&&|&|\s|->\s*[\w:<>,\s\*&]+|:\s*[\w:]+\s*[({].*)*$", flat)
                if (sig and sig.group(1).split("::")[-1] not in CONTROL and
                        not re.search(r"\b(namespace|class|struct|union|enum)\b[^()]*$", flat)):
                    entry = ("function", sig.group(1), code.count("\n", 0, i) + 1)
            stack.append(entry)
            segment_start = i + 1
        elif c == "}":
            if stack:
                kind, name, first = stack.pop()
                if kind == "function":
                    found.append((name, first, code.count("\n", 0, i) + 1 - first + 1))
            segment_start = i + 1
        elif c == ";":
            segment_start = i + 1
    return found


def measure():
    sizes = {}
    for rel, text in cpp_lex.sources(REPO, DIRS):
        lines = text.count("\n")
        if lines > FILE_LIMIT:
            sizes[rel] = lines
        for fn, first, count in functions(text):
            if count > FUNCTION_LIMIT:
                key = f"{rel}:{fn}"
                sizes[key] = max(sizes.get(key, 0), count)
    return sizes


def main():
    sizes = measure()
    if "--record" in sys.argv[1:]:
        with open(KNOWN, "w") as out:
            out.write("# Files over 900 lines and functions over 200 written before the limits were checked\n"
                      "# (scripts/check-sizes.py): each may shrink, not grow. Lines: path[:function] length.\n")
            for key in sorted(sizes):
                out.write(f"{key} {sizes[key]}\n")
        print(f"check-sizes: recorded {len(sizes)} known over-limit files and functions in {KNOWN}")
        return 0
    known = {}
    if os.path.exists(KNOWN):
        for line in open(KNOWN):
            line = line.strip()
            if line and not line.startswith("#"):
                key, count = line.rsplit(" ", 1)
                known[key] = int(count)
    problems = []
    for key, count in sorted(sizes.items()):
        limit = FILE_LIMIT if ":" not in key else FUNCTION_LIMIT
        what = "file" if ":" not in key else "function"
        if key not in known:
            problems.append(f"{key}: {what} of {count} lines, over the limit of {limit}")
        elif count > known[key]:
            problems.append(f"{key}: {what} grew from {known[key]} to {count} lines (limit {limit}; split it)")
    for line in problems:
        print("check-sizes: " + line, file=sys.stderr)
    if problems:
        return 1
    print(f"check-sizes: no new file over {FILE_LIMIT} lines or function over {FUNCTION_LIMIT}; "
          f"{len(sizes)} older ones, none grown")
    return 0


if __name__ == "__main__":
    sys.exit(main())
