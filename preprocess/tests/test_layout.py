"""The package's shape: the library never imports the command line, and no import cycles."""

import ast
import pathlib

import loudscape_extract

PACKAGE = pathlib.Path(loudscape_extract.__file__).parent


def _modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        yield name, ast.parse(path.read_text(encoding="utf-8"))


def _imports(tree, *, top_level_only):
    nodes = tree.body if top_level_only else ast.walk(tree)
    for node in nodes:
        if isinstance(node, ast.ImportFrom) and node.module:
            yield node.module
        elif isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)


def _graph():
    modules = dict(_modules())
    graph = {}
    for name, tree in modules.items():
        graph[name] = {
            target
            for target in _imports(tree, top_level_only=False)
            if target in modules and target != name
        }
    return modules, graph


def test_library_never_imports_the_command_line():
    _, graph = _graph()
    users = sorted(name for name, targets in graph.items() if "loudscape_extract.cli" in targets)
    assert users == []


def test_no_package_import_hidden_inside_a_function():
    modules, _ = _graph()
    hidden = []
    for name, tree in modules.items():
        everywhere = set(_imports(tree, top_level_only=False))
        top = set(_imports(tree, top_level_only=True))
        hidden += [(name, t) for t in everywhere - top if t.startswith("loudscape_extract")]
    assert hidden == []


def test_no_import_cycle():
    _, graph = _graph()
    # A package's __init__ re-exports its modules; importing the package from one of its own
    # modules would be a cycle, so the edge counts like any other.
    state = {}
    cycle = []

    def visit(node, stack):
        state[node] = "open"
        for target in sorted(graph[node]):
            if state.get(target) == "open":
                cycle.extend(stack[stack.index(target) :] + [target])
                return True
            if target not in state and visit(target, stack + [target]):
                return True
        state[node] = "done"
        return False

    for node in sorted(graph):
        if node not in state and visit(node, [node]):
            break
    assert cycle == []


def test_no_module_over_800_lines():
    long = {
        str(path.relative_to(PACKAGE)): n
        for path in PACKAGE.rglob("*.py")
        if (n := len(path.read_text(encoding="utf-8").splitlines())) > 800
    }
    assert long == {}
