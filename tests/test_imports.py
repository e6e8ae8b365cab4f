"""The layering, checked by parsing every import: no circle, nothing below treesketch/ imports
it, and no module imports another module's private (underscore) name."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# benchmarks: the scripts' package, above the product
LAYERS = ["weberpenn", "render", "tsn", "refine", "eval", "treesketch", "benchmarks"]


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in LAYERS:
        for f in (ROOT / pkg).rglob("*.py"):
            rel = f.relative_to(ROOT).with_suffix("")
            parts = list(rel.parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = f
    return out


def _imports(name: str, path: Path) -> list[tuple[str, list[str], int]]:
    """(absolute module, imported names, line) for every import in the file."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(a.name, [], node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            found.append((mod, [a.name for a in node.names], node.lineno))
    return found


def _graph() -> dict[str, set[str]]:
    mods = _modules()
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for name, path in mods.items():
        for mod, names, _ in _imports(name, path):
            targets = [f"{mod}.{n}" for n in names]
            if not name.startswith(mod + "."):  # a module's own package __init__ is no edge
                targets.append(mod)
            graph[name] |= {t for t in targets if t in mods and t != name}
    return graph


def test_lower_packages_never_import_treesketch() -> None:
    for name, path in _modules().items():
        if LAYERS.index(name.split(".")[0]) >= LAYERS.index("treesketch"):
            continue
        for mod, _, line in _imports(name, path):
            assert mod.split(".")[0] != "treesketch", f"{path}:{line} imports {mod}"


def test_packages_depend_only_leftwards() -> None:
    rank = {p: i for i, p in enumerate(LAYERS)}
    for name, path in _modules().items():
        own = rank[name.split(".")[0]]
        for mod, _, line in _imports(name, path):
            top = mod.split(".")[0]
            if top in rank:
                assert rank[top] <= own, f"{path}:{line}: {name} imports {mod}"


def test_no_private_names_across_modules() -> None:
    mods = _modules()
    for name, path in mods.items():
        for mod, names, line in _imports(name, path):
            if mod.split(".")[0] not in LAYERS:
                continue
            for n in names:
                assert not n.startswith("_"), f"{path}:{line} imports private {mod}.{n}"
            private = [p for p in mod.split(".") if p.startswith("_") and p != "__init__"]
            if private:  # a private module only from inside its own package
                owner = mod.rpartition(".")[0]
                assert name == owner or name.startswith(owner + "."), (
                    f"{path}:{line} imports private module {mod}"
                )


def test_no_import_circles() -> None:
    graph = _graph()
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for n in sorted(graph[m]):
            if state.get(n) == 1:
                cycle = stack[stack.index(n) :] + [n]
                raise AssertionError("import circle: " + " -> ".join(cycle))
            elif n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m)
