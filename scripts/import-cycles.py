#!/usr/bin/env python3
"""Import circles between the modules of a Rust crate.

Usage: scripts/import-cycles.py [SRC_DIR ...]   (default: crates/drape/src)

Within every module that has children, the children (a file, or a folder
with all below it) are the nodes of a graph: A -> B when code in A names
something of B (`use crate::...`, `use super::...`, or a path such as
`crate::solver::LinearMode` in the code). A circle is a set of siblings
that reach each other. A module's own file (`mod.rs`) is their parent,
not one of them: a child using its parent's items, or the parent
declaring and re-exporting its children, is no circle. A name the parent
only re-exports (`pub use child::Name`) counts as the child's. Tests
(`#[cfg(test)]`, `#[cfg(all(test, ...))]` items) are left out: they may use anything.

Prints each circle with the references that make it, and exits 1 if there
is any, 0 if there is none.
"""

import os
import re
import sys


def strip_comments_and_strings(text):
    """The code with comments, string and char literals blanked."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and not (
            i and (text[i - 1].isalnum() or text[i - 1] == "_")
        ):
            hashes = re.match(r"r(#*)\"", text[i:]).group(1)
            end = text.find('"' + hashes, i + 2 + len(hashes))
            out.append('""')
            i = n if end < 0 else end + 1 + len(hashes)
        elif c == '"':
            i += 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == "\\" else 1
            out.append('""')
            i += 1
        elif c == "'" and re.match(r"'(\\.|[^\\'])'", text[i:i + 4]) or (
            c == "'" and text.startswith("'\\", i)
        ):
            end = text.find("'", i + 2)
            out.append("' '")
            i = end + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def strip_tests(code):
    """The code without `#[cfg(test)]` items (a module's braces, or one item)."""
    while True:
        m = re.search(r"#\[cfg\((?:all\()?test\b[^\]]*\]", code)
        if not m:
            return code
        j = m.end()
        # The item's braces, or its end at `;` (a `use` or `mod x;`).
        k = j
        while k < len(code) and code[k] not in "{;":
            k += 1
        if k < len(code) and code[k] == "{":
            depth = 0
            while k < len(code):
                if code[k] == "{":
                    depth += 1
                elif code[k] == "}":
                    depth -= 1
                    if depth == 0:
                        break
                k += 1
        code = code[: m.start()] + code[k + 1:]


def expand_use(tree):
    """`a::{b, c::{d, e}}` -> [['a','b'], ['a','c','d'], ['a','c','e']]."""
    tree = re.sub(r"\s*([:{},])\s*", r"\1", tree.strip())

    def parse(s, i):
        # Returns (list of paths, next index) for a comma-separated list.
        paths, cur = [], []
        prefix = ""
        while i < len(s):
            c = s[i]
            if c == "{":
                inner, i = parse(s, i + 1)
                base = [p for p in prefix.split("::") if p]
                paths.extend(base + p for p in inner)
                prefix = ""
                continue
            if c == "}":
                if prefix:
                    paths.append([p for p in prefix.split("::") if p])
                return paths, i + 1
            if c == ",":
                if prefix:
                    paths.append([p for p in prefix.split("::") if p])
                prefix = ""
                i += 1
                continue
            prefix += c
            i += 1
        if prefix:
            paths.append([p for p in prefix.split("::") if p])
        return paths, i

    paths, _ = parse(tree, 0)
    # `x as y` names x.
    return [[seg.split()[0] for seg in p] for p in paths]


def module_of(src, path):
    """The module path (a tuple) of the file at `path` below `src`."""
    rel = os.path.relpath(path, src)[:-3].split(os.sep)
    if rel[-1] in ("lib", "main", "mod"):
        rel = rel[:-1]
    return tuple(rel)


def read_crate(src):
    files = {}
    for root, _, names in os.walk(src):
        for name in names:
            if name.endswith(".rs"):
                path = os.path.join(root, name)
                with open(path, encoding="utf-8") as f:
                    code = strip_tests(strip_comments_and_strings(f.read()))
                files[module_of(src, path)] = (path, code)
    return files


USE = re.compile(r"\b(pub(\([^)]*\))?\s+)?use\s+([^;]+);")
PATH = re.compile(r"\b((?:crate|super|self)(?:\s*::\s*\w+)+)")


def absolute(module, segments):
    """A path as written in `module` made absolute, or None (an extern crate)."""
    out = list(module)
    segs = list(segments)
    if segs and segs[0] == "crate":
        return tuple(segs[1:])
    if not segs or segs[0] not in ("super", "self"):
        return None
    while segs and segs[0] in ("super", "self"):
        if segs.pop(0) == "super":
            if not out:
                return None
            out.pop()
    return tuple(out + segs)


def main(argv):
    srcs = argv[1:] or ["crates/drape/src"]
    found = False
    for src in srcs:
        found |= check(src)
    return 1 if found else 0


def check(src):
    files = read_crate(src)
    modules = set(files)
    # Re-exports: (module, name) -> absolute path it stands for.
    reexports = {}
    uses = {}  # module -> list of (absolute path, text written)
    for module, (_, code) in files.items():
        refs = []
        for m in USE.finditer(code):
            for p in expand_use(m.group(3)):
                whole = absolute(module, p)
                if whole is None:
                    continue
                if m.group(1) and whole[-1] != "*":
                    reexports[(module, whole[-1])] = whole
                    continue
                refs.append((whole, "use " + "::".join(p)))
        body = USE.sub("", code)
        for m in PATH.finditer(body):
            p = [s.strip() for s in m.group(1).split("::")]
            whole = absolute(module, p)
            if whole is not None:
                refs.append((whole, "::".join(p)))
        uses[module] = refs

    def resolve(path, seen=0):
        """The module that `path` names (or that holds the item it names)."""
        path = tuple(s for s in path if s != "*")
        for k in range(len(path), -1, -1):
            head = path[:k]
            if head in modules:
                if k < len(path) and (head, path[k]) in reexports and seen < 20:
                    return resolve(reexports[(head, path[k])] + path[k + 1:], seen + 1)
                return head
        return ()

    # Sibling edges under every parent.
    edges = {}  # parent -> {a: {b: [(file, text)]}}
    for module, refs in uses.items():
        for whole, text in refs:
            target = resolve(whole)
            # The deepest common parent, and the two children under it.
            k = 0
            while k < min(len(module), len(target)) and module[k] == target[k]:
                k += 1
            if k == len(module) or k == len(target):
                continue  # one is the other's ancestor
            parent = module[:k]
            a, b = module[k], target[k]
            edges.setdefault(parent, {}).setdefault(a, {}).setdefault(b, []).append(
                (files[module][0], text)
            )

    found = False
    for parent in sorted(edges):
        graph = edges[parent]
        for scc in strongly_connected(graph):
            if len(scc) < 2:
                continue
            found = True
            where = "::".join(("crate",) + parent)
            print(f"circle under {where}: {', '.join(sorted(scc))}")
            for a in sorted(scc):
                for b in sorted(graph.get(a, {})):
                    if b in scc:
                        for path, text in sorted(set(graph[a][b])):
                            print(f"  {a} -> {b}: {path}: {text}")
    if not found:
        print(f"{src}: no import circles")
    return found


def strongly_connected(graph):
    """Tarjan's strongly connected components of {node: {node: ...}}."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]
    nodes = set(graph) | {b for a in graph for b in graph[a]}

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, {}):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc = set()
            while True:
                w = stack.pop()
                on.discard(w)
                scc.add(w)
                if w == v:
                    break
            out.append(scc)

    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return out


if __name__ == "__main__":
    sys.exit(main(sys.argv))
