"""src/'s folders and which may include which (docs/layering.md).

Each folder of src/ is a layer; a file may include headers of its own folder
and of the layers below it, never of a layer beside or above it. Internal
headers are included with their folder (``#include "map/tilemap.h"``), so
the rule can be read off the include lines alone.
"""

import re
from pathlib import Path

from conftest import REPO_ROOT

SRC = REPO_ROOT / "src"

# folder -> the folders its files may include besides their own
LAYERS = {
    "core": set(),
    "map": {"core"},
    "paper": {"core"},
    "drivers": {"core"},
    "localizer": {"core", "map", "paper"},
}

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def includes(path: Path):
    """The quoted includes of a source file, comments aside."""
    text = re.sub(r"/\*.*?\*/", "", path.read_text(), flags=re.S)
    return INCLUDE.findall(text)


def violations(tree):
    """Broken rules in ``tree`` ({folder: {file: [includes]}}), as strings."""
    out = []
    for folder, files in sorted(tree.items()):
        if folder not in LAYERS:
            out.append(f"src/{folder}: a folder docs/layering.md does not name")
            continue
        for name, incs in sorted(files.items()):
            for inc in incs:
                if inc.startswith("rsm/"):
                    continue
                if "/" not in inc:
                    out.append(f"src/{folder}/{name}: includes {inc} without its folder")
                    continue
                layer = inc.split("/", 1)[0]
                if layer != folder and layer not in LAYERS[folder]:
                    out.append(f"src/{folder}/{name}: includes {inc} ({layer} is not below {folder})")
    return out


def source_tree():
    tree = {}
    for p in sorted(SRC.rglob("*.[ch]")):
        rel = p.relative_to(SRC)
        folder = rel.parts[0] if len(rel.parts) > 1 else "."
        tree.setdefault(folder, {})[str(Path(*rel.parts[1:]) if len(rel.parts) > 1 else rel)] = includes(p)
    return tree


def test_every_source_file_is_in_a_layer_and_the_top_level_holds_none():
    tree = source_tree()
    assert "." not in tree, f"source files at src/'s top level: {sorted(tree.get('.', {}))}"
    assert set(tree) == set(LAYERS), f"folders {sorted(tree)} against the layers {sorted(LAYERS)}"
    for folder, files in tree.items():
        assert any(f.endswith(".c") for f in files), f"src/{folder} holds no source file"


def test_no_file_includes_a_layer_beside_or_above_its_own():
    problems = violations(source_tree())
    assert not problems, "\n".join(problems)


def test_the_rule_catches_a_driver_in_the_localizer_and_a_bare_include():
    # The checker itself: a map file that includes a driver's header, a core
    # file that includes the map, and an include without its folder.
    tree = {
        "map": {"tilemap.c": ["core/fmath.h", "drivers/stamps.h"]},
        "core": {"scan.c": ["map/tilemap.h", "rsm/scan.h"]},
        "localizer": {"localizer.c": ["map/tilemap.h", "paper/icp.h", "ekf.h"]},
    }
    problems = violations(tree)
    assert len(problems) == 3, problems
    assert any("drivers/stamps.h" in p for p in problems)
    assert any("src/core/scan.c" in p for p in problems)
    assert any("without its folder" in p for p in problems)


def test_the_layers_named_here_are_those_docs_layering_md_gives():
    doc = (REPO_ROOT / "docs" / "layering.md").read_text()
    for folder, below in LAYERS.items():
        row = re.search(rf"^\| `src/{folder}/` \|[^|]*\| ([^|]*) \|", doc, re.M)
        assert row, f"docs/layering.md has no row for src/{folder}/"
        named = set(re.findall(r"`src/([a-z]+)/`", row.group(1)))
        assert named == below, f"src/{folder}/: the doc says {sorted(named)}, the test {sorted(below)}"
