#!/usr/bin/env bash
# Fails, one line per violation naming the file, when the code leaves docs/layers.txt's graph:
#   - a CMake target in src/parallax/<layer>/ links a parallax_* target of a layer that is not a
#     direct edge of <layer> (of <layer> or its tests line, for a test target), or the graph
#     keeps an edge that no target links;
#   - a file in src/parallax/<layer>/ includes "parallax/<other>/..." where <other> cannot be
#     reached from <layer> along the graph (from the tests line too, for a test's file);
#   - the graph has a cycle, names a layer with no folder, or misses a folder of src/parallax/.
#   - docs/architecture.md's Layers table gives a layer other links than the graph does.
#   bash scripts/check-layers.sh [--root DIR]   checks the tree at DIR (default: this checkout)
#   bash scripts/check-layers.sh --self-test    a clean tree in /tmp passes, and one broken tree
#                                               per kind of violation fails, naming it
set -euo pipefail
exec python3 - "$0" "$@" <<'PY'
import os
import re
import shutil
import subprocess
import sys
import tempfile

GRAPH = "docs/layers.txt"
DOC = "docs/architecture.md"
LAYERS = "src/parallax"
SOURCE_EXTENSIONS = (".h", ".hh", ".hpp", ".cc", ".cpp", ".cxx", ".inl", ".ipp")
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"](parallax/([^/">]+)/[^">]*)[">]')
LINK_KEYWORDS = {"PUBLIC", "PRIVATE", "INTERFACE", "LINK_PUBLIC", "LINK_PRIVATE",
                 "LINK_INTERFACE_LIBRARIES", "debug", "optimized", "general"}
LIBRARY_KEYWORDS = {"STATIC", "SHARED", "MODULE", "OBJECT", "INTERFACE", "UNKNOWN",
                    "IMPORTED", "GLOBAL", "ALIAS", "EXCLUDE_FROM_ALL", "WIN32", "MACOSX_BUNDLE"}


def read_graph(root, errors):
    """Returns ({layer: [deps]}, {layer: [test deps]}, {(layer, is_test): line})."""
    deps, test_deps, lines = {}, {}, {}
    path = os.path.join(root, GRAPH)
    if not os.path.isfile(path):
        errors.append(f"{GRAPH}: missing")
        return deps, test_deps, lines
    with open(path, encoding="utf-8") as graph:
        for number, raw in enumerate(graph, 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            match = re.fullmatch(r"([A-Za-z0-9_]+)(\s+tests)?\s*:\s*(.*)", line)
            if not match:
                errors.append(f"{GRAPH}:{number}: cannot read '{line}' "
                              "(want 'layer: dep ...' or 'layer tests: dep ...')")
                continue
            layer, is_test = match.group(1), bool(match.group(2))
            table = test_deps if is_test else deps
            if layer in table:
                errors.append(f"{GRAPH}:{number}: '{layer}{' tests' if is_test else ''}' "
                              f"listed twice (first on line {lines[(layer, is_test)]})")
                continue
            table[layer] = match.group(3).split()
            lines[(layer, is_test)] = number
    return deps, test_deps, lines


def check_graph(root, deps, test_deps, lines, errors):
    folders = sorted(name for name in os.listdir(os.path.join(root, LAYERS))
                     if os.path.isdir(os.path.join(root, LAYERS, name)))
    for folder in folders:
        if folder not in deps:
            errors.append(f"{LAYERS}/{folder}/: a layer folder that {GRAPH} does not list")
    for layer in deps:
        if layer not in folders:
            errors.append(f"{GRAPH}:{lines[(layer, False)]}: unknown layer '{layer}' "
                          f"(no {LAYERS}/{layer}/)")
    for is_test, table in ((False, deps), (True, test_deps)):
        for layer, names in table.items():
            where = f"{GRAPH}:{lines[(layer, is_test)]}"
            if is_test and layer not in deps:
                errors.append(f"{where}: unknown layer '{layer}' (tests of a layer the graph "
                              "does not list)")
            for name in names:
                if name not in deps:
                    errors.append(f"{where}: unknown layer '{name}' in {layer}'s edges")
    # Cycles, each reported once, by a depth-first walk over the library edges.
    state, stack, reported = {}, [], set()

    def visit(layer):
        state[layer] = "open"
        stack.append(layer)
        for dep in deps.get(layer, []):
            if dep not in deps:
                continue
            if state.get(dep) == "open":
                cycle = stack[stack.index(dep):] + [dep]
                key = frozenset(cycle)
                if key not in reported:
                    reported.add(key)
                    errors.append(f"{GRAPH}:{lines[(layer, False)]}: cycle "
                                  + " -> ".join(cycle))
            elif dep not in state:
                visit(dep)
        stack.pop()
        state[layer] = "done"

    for layer in deps:
        if layer not in state:
            visit(layer)


def check_doc(root, deps, errors):
    """The Layers table of docs/architecture.md: a row per layer, its links the graph's edges."""
    path = os.path.join(root, DOC)
    if not os.path.isfile(path):
        return
    rows, in_layers = {}, False
    with open(path, encoding="utf-8") as doc:
        for number, line in enumerate(doc, 1):
            if line.startswith("## "):
                in_layers = line.strip() == "## Layers"
                continue
            match = re.match(r"\|\s*`([^`]+)`\s*\|", line)
            if not in_layers or not match:
                continue
            layer = match.group(1)
            links = [item.strip() for item in line.rstrip().rstrip("|").split("|")[-1].split(",")]
            rows[layer] = number
            if layer not in deps:
                errors.append(f"{DOC}:{number}: the Layers table has a row for '{layer}', "
                              f"a layer {GRAPH} does not list")
                continue
            named = [item for item in links if item in deps]
            if sorted(named) != sorted(deps[layer]):
                errors.append(f"{DOC}:{number}: the Layers table gives {layer} the links "
                              f"'{', '.join(named) or 'none'}', {GRAPH} the edges "
                              f"'{', '.join(deps[layer]) or 'none'}'")
    for layer in deps:
        if layer not in rows:
            errors.append(f"{DOC}: the Layers table has no row for '{layer}'")


def reachable(deps, start):
    """The layers reachable from the layers in `start` (themselves included)."""
    seen, todo = set(), list(start)
    while todo:
        layer = todo.pop()
        if layer in seen:
            continue
        seen.add(layer)
        todo.extend(dep for dep in deps.get(layer, []) if dep in deps)
    return seen


def strip_comments(text):
    """CMake text without its # comments (quoted strings kept), newlines kept."""
    out, in_quote, i = [], False, 0
    while i < len(text):
        c = text[i]
        if in_quote:
            out.append(c)
            if c == "\\" and i + 1 < len(text):
                out.append(text[i + 1])
                i += 1
            elif c == '"':
                in_quote = False
        elif c == '"':
            in_quote = True
            out.append(c)
        elif c == "#":
            while i < len(text) and text[i] != "\n":
                i += 1
            continue
        else:
            out.append(c)
        i += 1
    return "".join(out)


def cmake_commands(text):
    """(name, [args], line) for each command of a CMake file."""
    text = strip_comments(text)
    command = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s*\(")
    pos = 0
    while True:
        match = command.search(text, pos)
        if not match:
            return
        depth, i, in_quote = 1, match.end(), False
        while i < len(text) and depth:
            c = text[i]
            if in_quote:
                if c == "\\":
                    i += 1
                elif c == '"':
                    in_quote = False
            elif c == '"':
                in_quote = True
            elif c == "(":
                depth += 1
            elif c == ")":
                depth -= 1
            i += 1
        span = text[match.end():i - 1]
        args = [quoted if quoted else bare for quoted, bare in
                re.findall(r'"((?:[^"\\]|\\.)*)"|([^\s()"]+)', span)]
        yield match.group(1).lower(), args, text.count("\n", 0, match.start()) + 1
        pos = i


def keyword_values(args, keyword, keywords):
    values, current = [], None
    for arg in args:
        if arg in keywords:
            current = arg
        elif current == keyword:
            values.append(arg)
    return values


def read_targets(root, layer, errors):
    """The targets the CMake files of one layer folder define, with their links."""
    targets = []  # dicts: name, layer, test, links [(token, file, line)], file, line
    by_name = {}
    test_sources = set()
    folder = os.path.join(root, LAYERS, layer)
    for directory, subdirectories, files in os.walk(folder):
        subdirectories.sort()
        if "CMakeLists.txt" not in files:
            continue
        path = os.path.join(directory, "CMakeLists.txt")
        relative = os.path.relpath(path, root)
        with open(path, encoding="utf-8") as cmake:
            text = cmake.read()
        conditions = []  # per open if(): whether it is on PARALLAX_BUILD_TESTS

        def add(name, test, line):
            target = {"name": name, "layer": layer, "test": test, "links": [],
                      "file": relative, "line": line}
            targets.append(target)
            by_name[name] = target
            return target

        def sources(args):
            for arg in args:
                arg = arg.replace("${CMAKE_CURRENT_SOURCE_DIR}/", "")
                if arg.endswith(SOURCE_EXTENSIONS) and "$" not in arg:
                    test_sources.add(os.path.normpath(os.path.join(directory, arg)))

        for name, args, line in cmake_commands(text):
            in_tests = any(conditions)
            if name == "if":
                conditions.append("PARALLAX_BUILD_TESTS" in args)
            elif name == "elseif":
                if conditions:
                    conditions[-1] = "PARALLAX_BUILD_TESTS" in args
            elif name == "else":
                if conditions:
                    conditions[-1] = False
            elif name == "endif":
                if conditions:
                    conditions.pop()
            elif name == "parallax_add_library":
                keywords = {"NAME", "DEPS", "EXCLUDE"}
                names = keyword_values(args, "NAME", keywords)
                target = add(f"parallax_{names[0] if names else '?'}", in_tests, line)
                target["links"] += [(dep, relative, line)
                                    for dep in keyword_values(args, "DEPS", keywords)]
            elif name == "parallax_add_tests":
                keywords = {"NAME", "DEPS"}
                names = keyword_values(args, "NAME", keywords)
                target = add(f"{names[0] if names else '?'} tests", True, line)
                target["links"] += [(dep, relative, line)
                                    for dep in keyword_values(args, "DEPS", keywords)]
            elif name in ("add_library", "add_executable") and args:
                if "ALIAS" in args or "IMPORTED" in args:
                    continue
                add(args[0], in_tests, line)
                if in_tests:
                    sources(args[1:])
            elif name == "target_link_libraries" and args:
                target = by_name.get(args[0])
                if target is None:
                    errors.append(f"{relative}:{line}: target_link_libraries({args[0]} ...) on "
                                  "a target this folder does not define")
                    continue
                target["links"] += [(arg, relative, line) for arg in args[1:]
                                    if arg not in LINK_KEYWORDS]
            elif name == "target_sources" and args:
                target = by_name.get(args[0])
                if (target is not None and target["test"]) or args[0].endswith("_test"):
                    sources(args[1:])
    return targets, test_sources


def check_links(deps, test_deps, targets, errors):
    known = {target["name"]: target for target in targets}
    for target in targets:
        if target["name"].startswith("parallax_") and target["name"][9:] in deps \
                and target["name"][9:] != target["layer"]:
            errors.append(f"{target['file']}:{target['line']}: defines {target['name']} in "
                          f"{LAYERS}/{target['layer']}/, not in {LAYERS}/{target['name'][9:]}/")
    used = set()  # (layer, is_test, dep layer)
    for target in targets:
        layer = target["layer"]
        if layer not in deps:
            continue
        allowed = set(deps[layer])
        if target["test"]:
            allowed |= set(test_deps.get(layer, []))
        for token, file, line in target["links"]:
            if "$" in token or "::" in token:
                continue
            dependency = known.get(token)
            if dependency is None:
                if token.startswith("parallax_"):
                    errors.append(f"{file}:{line}: {target['name']} links {token}, "
                                  "a target no layer defines")
                continue
            other = dependency["layer"]
            if dependency["test"] and not target["test"]:
                errors.append(f"{file}:{line}: {target['name']} links {token}, "
                              "which is built for the tests only")
                continue
            if other == layer:
                continue
            if dependency["test"]:
                # The test main and its kind: any test whose layer reaches their layer.
                test_reach = reachable(deps, [layer] + test_deps.get(layer, []))
                if other not in test_reach:
                    errors.append(f"{file}:{line}: {target['name']} links {token} "
                                  f"({other}), which {layer}'s tests cannot reach in {GRAPH}")
                continue
            if other not in allowed:
                listed = " ".join(sorted(allowed)) or "nothing"
                errors.append(f"{file}:{line}: {target['name']} links {token}: "
                              f"{layer} -> {other} is not an edge of {GRAPH} "
                              f"({layer}{' tests' if target['test'] else ''} may link: {listed})")
                continue
            if not target["test"]:
                used.add((layer, False, other))
            elif other not in deps[layer]:
                used.add((layer, True, other))
    return used


def check_unused_edges(deps, test_deps, lines, used, errors):
    library_used = {(layer, dep) for layer, is_test, dep in used if not is_test}
    test_used = {(layer, dep) for layer, is_test, dep in used if is_test}
    for layer, names in deps.items():
        for dep in names:
            if dep in deps and (layer, dep) not in library_used:
                errors.append(f"{GRAPH}:{lines[(layer, False)]}: edge {layer} -> {dep} that no "
                              f"target of {LAYERS}/{layer}/ links (drop it from the graph)")
    for layer, names in test_deps.items():
        for dep in names:
            if dep in deps and (layer, dep) not in test_used:
                errors.append(f"{GRAPH}:{lines[(layer, True)]}: test edge {layer} -> {dep} that "
                              f"no test target of {LAYERS}/{layer}/ links (drop it from the graph)")


def is_test_file(path, test_sources):
    name = os.path.basename(path)
    parts = path.split(os.sep)
    return (re.search(r"_test\.[a-z]+$", name) is not None or "testing" in parts
            or os.path.normpath(path) in test_sources)


def check_includes(root, deps, test_deps, test_sources, errors):
    count = 0
    for layer in sorted(deps):
        folder = os.path.join(root, LAYERS, layer)
        if not os.path.isdir(folder):
            continue
        library_reach = reachable(deps, [layer])
        test_reach = reachable(deps, [layer] + test_deps.get(layer, []))
        for directory, subdirectories, files in os.walk(folder):
            subdirectories.sort()
            for name in sorted(files):
                if not name.endswith(SOURCE_EXTENSIONS):
                    continue
                path = os.path.join(directory, name)
                relative = os.path.relpath(path, root)
                test = is_test_file(path, test_sources)
                allowed = test_reach if test else library_reach
                with open(path, encoding="utf-8", errors="replace") as source:
                    for number, text in enumerate(source, 1):
                        match = INCLUDE.match(text)
                        if not match:
                            continue
                        count += 1
                        included, other = f'"{match.group(1)}"', match.group(2)
                        if other not in deps:
                            errors.append(f"{relative}:{number}: {layer} includes {included}: "
                                          f"unknown layer '{other}' (not in {GRAPH})")
                        elif other not in allowed:
                            errors.append(f"{relative}:{number}: {layer} includes {included}: "
                                          f"{layer}{' tests' if test else ''} -> {other} is not "
                                          f"reachable in {GRAPH}")
    return count


def check(root):
    errors = []
    deps, test_deps, lines = read_graph(root, errors)
    if not deps:
        return errors, "no graph"
    check_graph(root, deps, test_deps, lines, errors)
    check_doc(root, deps, errors)
    targets, test_sources = [], set()
    for layer in sorted(deps):
        if os.path.isdir(os.path.join(root, LAYERS, layer)):
            layer_targets, layer_test_sources = read_targets(root, layer, errors)
            targets += layer_targets
            test_sources |= layer_test_sources
    used = check_links(deps, test_deps, targets, errors)
    check_unused_edges(deps, test_deps, lines, used, errors)
    includes = check_includes(root, deps, test_deps, test_sources, errors)
    return errors, f"{len(deps)} layers, {len(targets)} targets, {includes} includes"


def run_check(root):
    errors, summary = check(root)
    for error in errors:
        print(f"check-layers: {error}", file=sys.stderr)
    if errors:
        print(f"check-layers: {len(errors)} violations of {GRAPH}", file=sys.stderr)
        return 1
    print(f"check-layers: {summary} and {DOC}'s Layers table agree with {GRAPH}")
    return 0


# A clean tree: util <- mid <- top, util <- side, and top's tests link side.
CLEAN = {
    GRAPH: "# test graph\nutil:\nmid: util\nside: util\ntop: mid\ntop tests: side\n",
    DOC: "# Architecture\n\n## Layers\n\n| folder | owns | links |\n|---|---|---|\n"
         "| `util` | checks | threads |\n| `mid` | middle | util |\n| `side` | aside | util, SQLite |\n"
         "| `top` | the top | mid |\n\n## Stages\n\n| `stage` | x | anything |\n",
    f"{LAYERS}/CMakeLists.txt": "add_subdirectory(util)\n",
    f"{LAYERS}/util/CMakeLists.txt":
        "parallax_add_library(NAME util EXCLUDE \"test_main\\\\.cc$\" DEPS Threads::Threads)\n"
        "if(PARALLAX_BUILD_TESTS)\n  add_library(parallax_test_main STATIC test_main.cc)\n"
        "  target_link_libraries(parallax_test_main PUBLIC parallax_util GTest::gtest)\nendif()\n"
        "parallax_add_tests(NAME util DEPS parallax_util)  # a comment: parallax_top\n",
    f"{LAYERS}/util/check.h": "#pragma once\n#include <string>\n",
    f"{LAYERS}/util/test_main.cc": "#include \"parallax/util/check.h\"\n",
    f"{LAYERS}/util/check_test.cc": "#include \"parallax/util/check.h\"\n",
    f"{LAYERS}/mid/CMakeLists.txt": "parallax_add_library(NAME mid DEPS parallax_util)\n",
    f"{LAYERS}/mid/mid.h": "#pragma once\n#include \"parallax/util/check.h\"\n"
                           "// #include \"parallax/top/top.h\" would be upward\n",
    f"{LAYERS}/side/CMakeLists.txt": "parallax_add_library(NAME side DEPS parallax_util)\n",
    f"{LAYERS}/side/side.h": "#pragma once\n#include \"parallax/util/check.h\"\n",
    f"{LAYERS}/top/CMakeLists.txt":
        "add_library(parallax_top INTERFACE)\n"
        "target_link_libraries(parallax_top INTERFACE parallax_mid)\n"
        "parallax_add_tests(NAME top DEPS parallax_top parallax_side)\n",
    f"{LAYERS}/top/top.h": "#pragma once\n#include \"parallax/util/check.h\"\n"
                           "#include \"parallax/mid/mid.h\"\n",
    f"{LAYERS}/top/top_test.cc": "#include \"parallax/side/side.h\"\n#include \"parallax/top/top.h\"\n",
    f"{LAYERS}/top/testing/scene.h": "#include \"parallax/side/side.h\"\n",
}

# One broken tree per kind of violation: (what, {file: new text or None to delete}, expected).
BROKEN = [
    ("a link the graph does not allow",
     {f"{LAYERS}/mid/CMakeLists.txt": "parallax_add_library(NAME mid DEPS parallax_util parallax_side)\n"},
     f"{LAYERS}/mid/CMakeLists.txt:1: parallax_mid links parallax_side: mid -> side"),
    ("a test link beyond the tests line",
     {f"{LAYERS}/util/CMakeLists.txt": CLEAN[f"{LAYERS}/util/CMakeLists.txt"].replace(
         "NAME util DEPS parallax_util)", "NAME util DEPS parallax_util parallax_mid)")},
     "util tests links parallax_mid: util -> mid"),
    ("a library linking the test main",
     {f"{LAYERS}/mid/CMakeLists.txt":
          "parallax_add_library(NAME mid DEPS parallax_util parallax_test_main)\n"},
     "parallax_mid links parallax_test_main, which is built for the tests only"),
    ("a link to a target no layer defines",
     {f"{LAYERS}/mid/CMakeLists.txt": "parallax_add_library(NAME mid DEPS parallax_util parallax_nowhere)\n"},
     "parallax_mid links parallax_nowhere, a target no layer defines"),
    ("an upward include",
     {f"{LAYERS}/mid/mid.h": "#pragma once\n#include \"parallax/top/top.h\"\n"},
     f"{LAYERS}/mid/mid.h:2: mid includes \"parallax/top/top.h\": mid -> top is not reachable"),
    ("a sideways include",
     {f"{LAYERS}/top/top.h": "#pragma once\n#include \"parallax/side/side.h\"\n"},
     f"{LAYERS}/top/top.h:2: top includes \"parallax/side/side.h\": top -> side"),
    ("a test include beyond the tests line",
     {f"{LAYERS}/mid/mid_test.cc": "#include \"parallax/side/side.h\"\n"},
     f"{LAYERS}/mid/mid_test.cc:1: mid includes \"parallax/side/side.h\": mid tests -> side"),
    ("the test main including upward",
     {f"{LAYERS}/util/test_main.cc": "#include \"parallax/mid/mid.h\"\n"},
     f"{LAYERS}/util/test_main.cc:1: util includes \"parallax/mid/mid.h\": util tests -> mid"),
    ("an include of a layer that does not exist",
     {f"{LAYERS}/top/top.h": "#include \"parallax/nowhere/x.h\"\n"},
     "unknown layer 'nowhere' (not in docs/layers.txt)"),
    ("a cycle",
     {GRAPH: CLEAN[GRAPH].replace("util:\n", "util: top\n"),
      f"{LAYERS}/util/CMakeLists.txt": "parallax_add_library(NAME util DEPS parallax_top)\n"},
     "cycle util -> top -> mid -> util"),
    ("an unknown layer in the graph",
     {GRAPH: CLEAN[GRAPH].replace("mid: util\n", "mid: util nowhere\n")},
     f"{GRAPH}:3: unknown layer 'nowhere' in mid's edges"),
    ("a graph layer without a folder",
     {GRAPH: CLEAN[GRAPH] + "ghost: util\n"},
     f"{GRAPH}:7: unknown layer 'ghost' (no {LAYERS}/ghost/)"),
    ("a layer folder the graph does not list",
     {f"{LAYERS}/extra/CMakeLists.txt": "parallax_add_library(NAME extra DEPS parallax_util)\n"},
     f"{LAYERS}/extra/: a layer folder that {GRAPH} does not list"),
    ("architecture.md's table giving other links",
     {DOC: CLEAN[DOC].replace("| `top` | the top | mid |", "| `top` | the top | mid, side |")},
     f"{DOC}:10: the Layers table gives top the links 'mid, side', {GRAPH} the edges 'mid'"),
    ("architecture.md's table missing a layer",
     {DOC: CLEAN[DOC].replace("| `side` | aside | util, SQLite |\n", "")},
     f"{DOC}: the Layers table has no row for 'side'"),
    ("an edge no target links",
     {GRAPH: CLEAN[GRAPH].replace("top: mid\n", "top: mid side\n")},
     "edge top -> side that no target"),
]


def write_tree(root, files):
    for path, text in files.items():
        full = os.path.join(root, path)
        if text is None:
            if os.path.exists(full):
                os.remove(full)
            continue
        os.makedirs(os.path.dirname(full), exist_ok=True)
        with open(full, "w", encoding="utf-8") as out:
            out.write(text)


def self_test(script):
    base = tempfile.mkdtemp(prefix="check-layers.", dir="/tmp")
    failures = []
    try:
        cases = [("a clean tree", {}, None)] + BROKEN
        for index, (what, changes, expected) in enumerate(cases):
            root = os.path.join(base, f"tree{index}")
            write_tree(root, CLEAN)
            write_tree(root, changes)
            run = subprocess.run(["bash", script, "--root", root], capture_output=True, text=True)
            output = run.stdout + run.stderr
            if expected is None:
                ok = run.returncode == 0
            else:
                ok = run.returncode != 0 and any(
                    expected in line for line in output.splitlines())
            if not ok:
                failures.append(f"{what}: exit {run.returncode}, wanted "
                                f"{'0' if expected is None else repr(expected)}; got:\n{output}")
            print(f"check-layers --self-test: {'ok  ' if ok else 'FAIL'} {what}")
    finally:
        shutil.rmtree(base)
    for failure in failures:
        print(f"check-layers --self-test: {failure}", file=sys.stderr)
    if failures:
        return 1
    print(f"check-layers --self-test: {len(BROKEN)} broken trees caught, the clean one passes")
    return 0


def main():
    script, args = sys.argv[1], sys.argv[2:]
    root = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(script)), ".."))
    if args == ["--self-test"]:
        return self_test(os.path.abspath(script))
    if len(args) == 2 and args[0] == "--root":
        root = args[1]
    elif args:
        print("usage: bash scripts/check-layers.sh [--root DIR | --self-test]", file=sys.stderr)
        return 2
    return run_check(root)


sys.exit(main())
PY
