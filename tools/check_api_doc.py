#!/usr/bin/env python3
"""Check that docs/api.md lists the public surface exactly.

The public surface is what `cmake --install` puts in include/rsm/: every
header there and every function (or function-like macro named rsm_*) it
declares. docs/api.md must name each header as `rsm/NAME.h` and each
function by name; it must not name as installed a header that include/rsm/
does not hold; and every internal header (src/*/*.h) must be named in its
internal section, so that a header moved in or out shows up here.
Problems are printed one a line and the exit status is 1; 0 means the page
is consistent; 2 is a usage error.

Pure Python 3 standard library.
"""

import argparse
import pathlib
import re
import sys

COMMENT = re.compile(r"/\*.*?\*/", re.S)
FUNCTION = re.compile(r"^[a-z_][a-z_0-9 \*]*?\b(rsm_[a-z0-9_]+)\s*\(", re.M)
MACRO = re.compile(r"^#define (rsm_[a-z0-9_]+)\(", re.M)
INSTALLED = re.compile(r"`rsm/([a-z0-9_]+\.h)`")


def declared(header: pathlib.Path) -> list:
    text = COMMENT.sub("", header.read_text(encoding="utf-8"))
    names = [m.group(1) for m in FUNCTION.finditer(text)] + [m.group(1) for m in MACRO.finditer(text)]
    return list(dict.fromkeys(names))


def check(root: pathlib.Path) -> list:
    doc_path = root / "docs" / "api.md"
    doc = doc_path.read_text(encoding="utf-8")
    internal = doc.split("## Internal", 1)[1] if "## Internal" in doc else ""
    problems = []
    headers = sorted((root / "include" / "rsm").glob("*.h"))
    for h in headers:
        if f"`rsm/{h.name}`" not in doc:
            problems.append(f"{doc_path}: installed header rsm/{h.name} is not listed")
        for name in declared(h):
            if not re.search(rf"`{name}`", doc):
                problems.append(f"{doc_path}: {name} (rsm/{h.name}) is not listed")
    names = {h.name for h in headers}
    for listed in sorted(set(INSTALLED.findall(doc))):
        if listed not in names:
            problems.append(f"{doc_path}: rsm/{listed} is listed but not in include/rsm/")
    for h in sorted((root / "src").glob("*/*.h")):
        if f"`{h.name}`" not in internal:
            problems.append(f"{doc_path}: internal header src/{h.parent.name}/{h.name} is not in the internal section")
    return problems


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    ap.add_argument("--root", type=pathlib.Path, default=pathlib.Path(__file__).resolve().parent.parent,
                    help="repository root (default: the parent of this script's folder)")
    args = ap.parse_args()
    try:
        problems = check(args.root)
    except OSError as e:
        print(f"check_api_doc: {e}", file=sys.stderr)
        return 2
    for p in problems:
        print(p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
