#!/usr/bin/env python3
"""Copies pictures out of a `rigbake validate` report.html into PNG files, for the docs.

Usage: doc-report-pictures.py REPORT.html ALT_PREFIX OUT.png [ALT_PREFIX OUT.png ...]

Each picture is the first <img> whose alt text starts with ALT_PREFIX (for example "crease elbow_r"),
written byte for byte as validate encoded it. Crease and muscle pictures are framed on the input
skinning (docs/deformation-quality.md, Pictures), so the same prefix taken from two bakes of one
character shows the same view: how docs/images/*-male-casual-*.png were made.
"""
import base64
import html
import re
import sys


def main(argv):
    if len(argv) < 4 or len(argv) % 2 != 0:
        sys.stderr.write(__doc__)
        return 1
    text = open(argv[1], encoding="utf-8").read()
    pictures = [(html.unescape(m.group(1)), m.group(2))
                for m in re.finditer(r'<img alt="([^"]*)"[^>]*src="data:image/png;base64,([^"]+)"', text)]
    for prefix, out in zip(argv[2::2], argv[3::2]):
        found = next((data for alt, data in pictures if alt.startswith(prefix)), None)
        if found is None:
            sys.stderr.write(f"{argv[1]}: no picture whose alt text starts with {prefix!r}\n")
            return 1
        with open(out, "wb") as f:
            f.write(base64.b64decode(found))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
