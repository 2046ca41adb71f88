#!/usr/bin/env python3
"""Checks that every library folder includes only the folders CMake links it to.

The layering of docs/pipeline.md "Layering" is written once, in CMakeLists.txt: a library
`dentsim_<folder>` links the libraries of the layers below it (dentsim_add_library(...) and
target_link_libraries(dentsim_<folder> ...)). A header-only include of a folder it does not link
would still compile, so this check reads every `#include "<folder>/..."` of the library's sources
and fails on one whose folder is not the library's own or one it links directly. Nothing outside
cli/ may include cli/. Usage: check_layering.py SOURCE_DIR (exit 0: the layering holds)."""
import pathlib
import re
import sys

# A target inside a library's folder with links of its own: the HDAPI emulator (a shared object
# that builds its simulated Phantom from a scene's device section, as the simulator does).
SUBTARGETS = {"device/hdapi/emulator": "dentsim_hd_emulator"}


def cmake_links(root: pathlib.Path) -> dict:
    text = root.joinpath("CMakeLists.txt").read_text()
    text = re.sub(r"#[^\n]*", "", text)
    links: dict = {}
    for m in re.finditer(r"dentsim_add_library\(\s*(dentsim_\w+)\s+(\w+)([^)]*)\)", text):
        links.setdefault(m.group(1), set()).update(re.findall(r"dentsim_\w+", m.group(3)))
    for m in re.finditer(r"target_link_libraries\(\s*(dentsim_\w+)([^)]*)\)", text):
        links.setdefault(m.group(1), set()).update(re.findall(r"dentsim_\w+", m.group(2)))
    return links


def main() -> int:
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    links = cmake_links(root)
    text = re.sub(r"#[^\n]*", "", root.joinpath("CMakeLists.txt").read_text())
    libraries = set(re.findall(r"dentsim_add_library\(\s*dentsim_(\w+)", text))
    libraries |= set(re.findall(r"add_library\(\s*dentsim_(\w+)\s+STATIC", text))
    folders = {f for f in libraries if (root / f).is_dir()}
    include = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/', re.M)
    bad = []
    checked = 0
    for path in sorted(root.rglob("*")):
        if path.suffix not in (".h", ".cc") or "build" in path.relative_to(root).parts[:1]:
            continue
        rel = path.relative_to(root).as_posix()
        top = rel.split("/", 1)[0]
        target = next((t for sub, t in SUBTARGETS.items() if rel.startswith(sub + "/")), None)
        if target is None and top in folders:
            target = "dentsim_" + top
        for m in include.finditer(path.read_text(errors="replace")):
            inc = m.group(1)
            if inc == "cli" and top != "cli":
                bad.append(f"{rel}: includes cli/ (nothing outside cli/ may)")
            if target is None or inc == top:
                continue
            checked += 1
            if not (root / inc).is_dir() or ("dentsim_" + inc) in links.get(target, set()):
                continue
            if inc in folders or inc in ("cli", "validation", "view"):
                bad.append(f"{rel}: includes {inc}/ but {target} does not link dentsim_{inc} "
                           f"(CMakeLists.txt)")
    for b in bad:
        print("layering:", b)
    print(f"layering: {checked} cross-folder includes checked against CMake's links, "
          f"{len(bad)} outside them")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
