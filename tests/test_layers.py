"""The packages' layers: hdl (the units) below golden (their models) below scene (the
driver, the stages, the composed top) below sim (the simulators, their runners, the CLI)
below flows (place and route, proofs, sweeps, fuzzing, benchmarks, reports) below board
(the ULX3S: its top, its whole-frame simulation, its bitstream).
Every import in the tree, at the top of a module or inside a function, is read from the
source; a package imports nothing from a layer above it, and no modules import each other
in a circle."""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LAYERS = ["hdl", "golden", "scene", "sim", "flows", "board"]
# golden's command line (python -m golden run) reads and writes npz files with sim's helpers
ALLOWED_UP = {("golden.__main__", "sim")}


def modules():
    """{module name: path} of every module in the packages."""
    out = {}
    for pkg in LAYERS:
        for path in (ROOT / pkg).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def imports(name, path, known):
    """The project modules that module ``name`` imports (relative imports resolved)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([base] if base else []))
            targets = [f"{base}.{a.name}" for a in node.names]   # a name, or its module
        else:
            continue
        for t in targets:
            while t and t not in known:        # the most specific module it names
                t = t.rpartition(".")[0]
            if t and t != name:
                out.add(t)
    return out


def graph():
    known = modules()
    return {n: imports(n, p, known) for n, p in known.items()}


def test_no_package_imports_a_layer_above_it():
    bad = []
    for mod, deps in graph().items():
        rank = LAYERS.index(mod.split(".")[0])
        for d in deps:
            top = d.split(".")[0]
            if LAYERS.index(top) > rank and (mod, top) not in ALLOWED_UP:
                bad.append(f"{mod} imports {d}")
    assert not bad, bad


def test_no_import_cycles():
    g, state, cycles = graph(), {}, []

    def visit(n, stack):
        state[n] = "open"
        for d in sorted(g.get(n, ())):
            if state.get(d) == "open":
                cycles.append(stack[stack.index(d):] + [d])
            elif d not in state:
                visit(d, stack + [d])
        state[n] = "done"
    for n in sorted(g):
        if n not in state:
            visit(n, [n])
    assert not cycles, [" -> ".join(c) for c in cycles]


def test_the_reader_sees_imports():
    """The checks above are not vacuous: the graph holds the layers' known imports."""
    g = graph()
    assert "hdl.units" in g["scene.pipeline"] and "golden.raster" in g["scene.stages.raster"]
    assert "scene.driver" in g["sim.render"] or "scene" in g["sim.render"]


def test_no_private_amaranth_api():
    """Nothing imports a private Amaranth module (``amaranth.hdl._ast`` and the like), calls a
    private method of an Amaranth value (``_rhs_signals``: the schedule keeps its own record of
    operands, ``hdl/term.py``) or sets Amaranth's private flags (``_MustUse__used``: a unit
    never elaborated is made in a file whose first line tells Amaranth). Read from the syntax
    tree: every import and every attribute."""
    bad = []
    for name, path in modules().items():
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("amaranth"):
                mods = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                mods = [a.name for a in node.names if a.name.startswith("amaranth")]
            else:
                mods = []
            bad += [f"{name}: imports {m}" for m in mods
                    if any(p.startswith("_") for p in m.split(".")[1:])]
            if isinstance(node, ast.Attribute) and (
                    node.attr in ("_rhs_signals", "_lhs_signals")
                    or node.attr.startswith("_MustUse")):      # Amaranth's private flags
                bad.append(f"{name}: uses {node.attr}")
    assert not bad, bad
