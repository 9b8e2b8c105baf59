#!/usr/bin/env python3
"""The rooms check: every folder is one namespace and one target, and includes only what
docs/architecture.md's table allows.

    python3 scripts/check-rooms.py [ROOT]        check the tree (exit 1 naming file and line)
    python3 scripts/check-rooms.py --self-test   prove the check fails on a forbidden include,
                                                 a foreign namespace and a re-export

The table is the one under "## The rooms" in docs/architecture.md: a Markdown table whose
columns are folder | namespace | target | may include | job. "may include" lists folders
(comma-separated, as written in the folder column, without backquotes or the trailing slash);
"everything" allows every room but tests/; a folder may always include itself.
What is checked, for every .h/.cpp under a listed folder:
  - each `#include "a/b.h"` names a file of a listed folder (or of the generated message types,
    `peritwin_msgs/`, which count as messages/) that the including folder may include;
  - each `namespace X {` opened at the top level is the folder's namespace or one inside it
    (anonymous namespaces and std are allowed);
  - no `using messages::X;` outside messages/ (a name is spelled with its owner's namespace);
  - every folder holding sources is in a room, and a room may include only rooms above it.
"""
import os
import re
import sys

TABLE_HEADING = "## The rooms"
GENERATED = {"peritwin_msgs": "messages"}
SOURCE_EXT = (".h", ".cpp", ".hpp", ".cpp.in")


def read_table(architecture_md):
    rooms = {}
    with open(architecture_md, encoding="utf-8") as f:
        lines = f.read().split("\n")
    try:
        start = next(i for i, l in enumerate(lines) if l.strip() == TABLE_HEADING)
    except StopIteration:
        raise SystemExit(f"{architecture_md}: no '{TABLE_HEADING}' section")
    rows = []
    for line in lines[start + 1:]:
        if line.startswith("## "):
            break
        if line.startswith("|"):
            rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    if len(rows) < 3:
        raise SystemExit(f"{architecture_md}: the rooms table has no rows")
    for row in rows[2:]:
        if len(row) < 5:
            raise SystemExit(f"{architecture_md}: a rooms row needs 5 columns: {row}")
        folder = row[0].strip("`").rstrip("/")
        namespace = row[1].strip("`")
        may = row[3].replace("`", "")
        allowed = {"*"} if may.strip() == "everything" else {
            m.strip().rstrip("/") for m in may.split(",") if m.strip() and m.strip() != "—"}
        rooms[folder] = {"namespace": namespace, "may": allowed}
    return rooms


def room_of(path, rooms):
    best = None
    for folder in rooms:
        if (path == folder or path.startswith(folder + "/")) and (best is None or len(folder) > len(best)):
            best = folder
    return best


def check_file(path, text, rooms, errors):
    room = room_of(path, rooms)
    if room is None:
        return
    info = rooms[room]
    opened = False  # the room's namespace was opened: a plain `namespace detail {` is nested in it
    for n, line in enumerate(text.split("\n"), 1):
        m = re.match(r'\s*#\s*include\s+"([^"]+)"', line)
        if m:
            inc = m.group(1)
            if "/" not in inc:
                continue  # a file beside this one (e.g. a generated page)
            top = inc.split("/")[0]
            target = GENERATED.get(top) or room_of(inc, rooms)
            if target is None:
                errors.append(f"{path}:{n}: includes \"{inc}\", which is in no room of "
                              "docs/architecture.md")
            elif target != room and target not in info["may"] and not (
                    "*" in info["may"] and target != "tests"):
                errors.append(f"{path}:{n}: {room}/ may not include \"{inc}\" ({target}/): "
                              f"docs/architecture.md allows {', '.join(sorted(info['may'])) or 'nothing'}")
            continue
        m = re.match(r"namespace\s+([A-Za-z_][\w:]*)\s*\{", line)
        if m and info["namespace"].startswith("peritwin"):
            ns = m.group(1)
            own = ns == info["namespace"] or ns.startswith(info["namespace"] + "::")
            nested = opened and not ns.startswith("peritwin")
            opened = opened or own
            if ns != "std" and not own and not nested:
                errors.append(f"{path}:{n}: namespace {ns} in {room}/, whose namespace is "
                              f"{info['namespace']}")
        if room != "messages" and re.match(r"\s*using\s+(peritwin::)?messages::\w+\s*;", line):
            errors.append(f"{path}:{n}: re-exports a name of messages/ (spell it messages::...)")


def unlisted_sources(root, rooms):
    """Tracked-looking source folders that no row of the table covers (build trees excluded)."""
    errors = []
    for top in sorted(os.listdir(root)):
        base = os.path.join(root, top)
        if not os.path.isdir(base) or top.startswith((".", "build")):
            continue
        for dirpath, dirs, files in os.walk(base):
            dirs[:] = [d for d in dirs if not d.startswith((".", "build"))]
            rel = os.path.relpath(dirpath, root)
            if any(f.endswith(SOURCE_EXT) for f in files) and room_of(rel + "/x", rooms) is None:
                errors.append(f"{rel}/: holds sources but is in no room of docs/architecture.md")
    return errors


def table_order(rooms):
    """Dependencies point one way: every folder a room may include is a room above it."""
    errors = []
    order = list(rooms)
    for i, room in enumerate(order):
        for m in sorted(rooms[room]["may"] - {"*"}):
            if m not in rooms:
                errors.append(f"docs/architecture.md: {room}/ may include {m}/, which is no room")
            elif order.index(m) >= i:
                errors.append(f"docs/architecture.md: {room}/ may include {m}/, a room below it "
                              "(dependencies point up the table)")
    return errors


def check_tree(root, rooms):
    errors = table_order(rooms) + unlisted_sources(root, rooms)
    for folder in sorted(rooms):
        base = os.path.join(root, folder)
        if not os.path.isdir(base):
            errors.append(f"{folder}/: listed in docs/architecture.md but missing")
            continue
        for dirpath, _, files in os.walk(base):
            for name in sorted(files):
                if not name.endswith(SOURCE_EXT):
                    continue
                full = os.path.join(dirpath, name)
                rel = os.path.relpath(full, root)
                if room_of(rel, rooms) != folder:
                    continue  # a sub-room's file, checked with it
                with open(full, encoding="utf-8", errors="replace") as f:
                    check_file(rel, f.read(), rooms, errors)
    return errors


def self_test(root):
    rooms = read_table(os.path.join(root, "docs", "architecture.md"))
    cases = [
        ("solver/mesh/x.h", '#include "twin/twin.h"\n', "may not include"),
        ("core/x.h", '#include "messages/batch.h"\n', "may not include"),
        ("loads/x.h", '#include "tests/support/process.h"\n', "may not include"),
        ("solver/statics/x.cpp", "namespace peritwin::twin {\n}\n", "namespace"),
        ("twin/x.h", "namespace peritwin::twin {\nusing messages::Batch;\n}\n", "re-exports"),
        ("config/x.cpp", "namespace detail {\n}\n", "namespace"),
    ]
    ok = True
    for path, text, expect in cases:
        errors = []
        check_file(path, text, rooms, errors)
        if not any(expect in e for e in errors):
            print(f"self-test: {path} with {text.strip()!r} was not refused ({errors})")
            ok = False
    backwards = dict(rooms)
    backwards["core"] = {"namespace": "peritwin::core", "may": {"twin"}}
    if not any("a room below it" in e for e in table_order(backwards)):
        print("self-test: core/ allowed to include twin/ (below it) was not refused")
        ok = False
    allowed = []
    check_file("twin/x.h", '#include "messages/batch.h"\nnamespace peritwin::twin {\n'
               'namespace detail {\n}\n}\n', rooms, allowed)
    if allowed:
        print(f"self-test: an allowed include was refused: {allowed}")
        ok = False
    print("self-test: " + ("7 forbidden cases refused, 1 allowed case accepted" if ok else "FAILED"))
    return 0 if ok else 1


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    root = os.path.abspath(args[0] if args else os.path.join(os.path.dirname(__file__), ".."))
    if "--self-test" in sys.argv:
        return self_test(root)
    rooms = read_table(os.path.join(root, "docs", "architecture.md"))
    errors = check_tree(root, rooms)
    for e in errors:
        print(e)
    print(f"check-rooms: {len(rooms)} rooms, {len(errors)} violations")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
