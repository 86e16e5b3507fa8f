#!/usr/bin/env python3
"""Checks the layering of the sources from their #include lines.

Usage: check_layering.py [ROOT]   (ROOT: the source tree, default: this script's parent folder)

Fails (exit 1, one line per offending include) when
  - models/ includes integrators/, or integrators/ includes models/;
  - core/, models/ or integrators/ include experiments/ or cli/;
  - experiments/ includes cli/ (but for the forwarding headers directly in experiments/);
  - experiments/output/ includes experiments/studies/, experiments/commands/ or the registries
    (experiments/framework/catalog.hpp);
  - a study (experiments/studies/X.* and its parts X_*.*) includes another study's header;
  - or an include listed in KNOWN below no longer occurs (the list only shrinks).
"""
import pathlib
import re
import sys

# Includes that break the rules above and that the split of experiments/ by job has not removed
# yet (the list only shrinks; each one removed must leave it). Empty: every include follows the
# rules.
KNOWN: set = set()

INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')


def study_names(root: pathlib.Path):
    """The studies: the stems X of experiments/studies/X.hpp that are not a part of another one."""
    stems = {p.stem for p in (root / "experiments" / "studies").glob("*.hpp")}
    return {x for x in stems if not any(x.startswith(y + "_") for y in stems)}


def study_of(path: str, studies):
    """The study a file of experiments/studies/ belongs to: X for X.*, X_output.* and any other
    part X_PART.* (e.g. audit_checks.cpp) of study X; the file's own stem when none matches."""
    stem = pathlib.PurePosixPath(path).stem
    owners = [x for x in studies if stem == x or stem.startswith(x + "_")]
    return max(owners, key=len) if owners else stem


def rules(src: str, inc: str, studies=frozenset()):
    """The rules the include `inc` of the file `src` breaks (paths relative to the root)."""
    layer = src.split("/", 1)[0]
    target = inc.split("/", 1)[0]
    if layer == "models" and target == "integrators":
        yield "models/ must not include integrators/"
    if layer == "integrators" and target == "models":
        yield "integrators/ must not include models/"
    if layer in ("core", "models", "integrators") and target in ("experiments", "cli"):
        yield f"{layer}/ must not include {target}/"
    # (experiments/*.hpp themselves are the old paths' forwarding headers.)
    if layer == "experiments" and src.count("/") > 1 and target == "cli":
        yield "experiments/ must not include cli/"
    if src.startswith("experiments/output/"):
        if inc.startswith(("experiments/studies/", "experiments/commands/")):
            yield "experiments/output/ must not include a study or a command"
        if inc.startswith("experiments/framework/catalog."):
            yield "experiments/output/ must not include the registries (framework/catalog)"
    if src.startswith("experiments/studies/") and inc.startswith("experiments/studies/"):
        if study_of(src, studies) != study_of(inc, studies):
            yield "a study must not include another study"


def main() -> int:
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).parent.parent)
    bad = []
    seen = set()
    studies = study_names(root)
    for layer in ("core", "models", "integrators", "experiments", "cli"):
        for path in sorted((root / layer).rglob("*")):
            if path.suffix not in (".hpp", ".cpp", ".inc", ".h"):
                continue
            src = path.relative_to(root).as_posix()
            for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                m = INCLUDE.match(line)
                if not m:
                    continue
                if (src, m.group(1)) in KNOWN:
                    seen.add((src, m.group(1)))
                    continue
                bad += [f"{src}:{n}: includes {m.group(1)}: {why}" for why in rules(src, m.group(1), studies)]
    bad += [f"{src}: no longer includes {inc}: remove it from KNOWN in {pathlib.Path(__file__).name}"
            for src, inc in sorted(KNOWN - seen)]
    for line in bad:
        print(line)
    if bad:
        print(f"check_layering: {len(bad)} include(s) break the layering", file=sys.stderr)
        return 1
    print("check_layering: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
