"""The comments and literals of C++ source, for the source checks (check-sizes.py blanks them before it
matches braces; check-flag-names.py reads the string literals): one scanner, so a quote in a comment, a
'"' or a raw string cannot fool one check and not the other."""
import os
import re


def spans(text):
    """Yields (kind, start, end, body_start, body_end) for every comment ("comment"), string literal
    ("string", raw strings included) and character literal ("char"), in order: text[start:end] is the
    whole token, text[body_start:body_end] what is between its delimiters."""
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            yield "comment", i, j, i + 2, j
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            end = n if j < 0 else j + 2
            yield "comment", i, end, i + 2, n if j < 0 else j
            i = end
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                i += 1
                continue
            body_start = i + m.end()
            close = text.find(")" + m.group(1) + '"', body_start)
            body_end = n if close < 0 else close
            end = n if close < 0 else close + len(m.group(1)) + 2
            yield "string", i, end, body_start, body_end
            i = end
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            end = min(n, j + 1)
            yield ("string" if c == '"' else "char"), i, end, i + 1, min(n, j)
            i = end
        else:
            i += 1


def sources(repo, dirs):
    """Yields (path relative to `repo`, text) of every .cpp and .h file under the top-level `dirs`, the
    files of each directory in name order; a directory that is not there yields nothing."""
    for top in dirs:
        for dirpath, _, names in os.walk(os.path.join(repo, top)):
            for name in sorted(names):
                if name.endswith((".cpp", ".h")):
                    path = os.path.join(dirpath, name)
                    yield os.path.relpath(path, repo), open(path, encoding="utf-8", errors="replace").read()
