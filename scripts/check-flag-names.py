#!/usr/bin/env python3
"""Layers: only cli/ knows rigbake's command-line flags. A string literal outside cli/ (in formats/,
pipeline/, anatomy/, app/, runtime/, sample/, core/) that names a flag ("--muscles", "bake --jiggle")
puts a CLI's spelling into a stage whose callers may not have that flag (build has manifest keys, an
engine has neither); such a string says the fact in its own terms and cli/ (or build, as a manifest key)
adds the flag where it prints.

Usage: scripts/check-flag-names.py
Comments may name flags (they explain why to a reader of the code); string literals may not, except the
few listed in ALLOWED below, each with the reason it must stay.
"""
import os
import re
import sys

import cpp_lex

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DIRS = ["formats", "pipeline", "anatomy", "app", "runtime", "sample", "core"]
# A flag: "--" and a lowercase word, not inside a word or a longer dash run. CSS custom properties in
# report.html's style sheet ("--ok: #2e7d32", "var(--ink)") are not flags.
FLAG = re.compile(r"(?<![\w-])(?<!var\()--[a-z][a-z0-9-]*(?![\w-]*:)")

# (path, flag): a literal in that file may name that flag. Keep this list short and say why beside each.
ALLOWED = frozenset({
    # none today: the ninja file's command lines (`build --character`), once in pipeline/build_plan.cpp,
    # are written by cli/cmd_build.cpp and passed in as NinjaCommands.
})


def string_literals(text):
    """(line, contents) of every string literal; comments, char literals and raw strings are handled so
    a quote in a comment or a '"' cannot start a false string."""
    return [(text.count("\n", 0, start) + 1, text[body_start:body_end])
            for kind, start, _, body_start, body_end in cpp_lex.spans(text) if kind == "string"]


def main():
    problems = []
    for rel, text in cpp_lex.sources(REPO, DIRS):
        for line, literal in string_literals(text):
            for match in FLAG.finditer(literal):
                if (rel, match.group(0)) in ALLOWED:
                    continue
                at = line + literal.count("\n", 0, match.start())
                excerpt = literal[max(0, match.start() - 40):match.end() + 40].replace("\n", " ")
                problems.append(f"{rel}:{at}: a string names the flag {match.group(0)}: ...{excerpt}...")
    for problem in problems:
        print("check-flag-names: " + problem, file=sys.stderr)
    if problems:
        print("check-flag-names: say it in the stage's own terms; cli/ adds the flag where it prints "
              "(see FixableByOption and InvalidOption in core/error.h)", file=sys.stderr)
        return 1
    print(f"check-flag-names: no string literal in {', '.join(d + '/' for d in DIRS)} names a flag")
    return 0


if __name__ == "__main__":
    sys.exit(main())
