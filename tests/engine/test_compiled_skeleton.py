"""The compiled kernels keep one loop skeleton per coordinate map (issue 39: "no route re-implements panels or
rules"): the loop over panels × azimuth nodes × radial nodes that evaluates the half-vector slope map is
:func:`brdfnorm.engine.compiled.slopes.slope_loop` alone (the shaders' ``shader_grid`` and the microfacet
lobes' ``microfacet_grid`` pass it their weights), and the one of the lobe-aligned hemisphere map is
:func:`brdfnorm.engine.compiled.kernels.hemisphere` alone (``hemisphere_panels`` and ``hemisphere_sums`` run it
with their rules).

Read from the source (ast): a function's loop nests, each level named by the helpers of ``engine/compiled`` it calls
directly or through other helpers. A second function with a loop (over panels or cells) around a level that reaches
a map's azimuth helper around one that reaches its node helper, or a nest of three or more loops with the same
helpers level by level as another function's, is a second copy of a skeleton. (The fused global rule's grid fill,
``global_rule._fill``, loops over one case's azimuths and nodes of the slope map: not a panel loop, not counted.)"""

from __future__ import annotations

import ast

import pytest
from helpers.paths import SRC

COMPILED = SRC / "brdfnorm" / "engine" / "compiled"
#: Each map: (the helper of its azimuth level, the helper of its node level) and the one function that loops over
#: them.
MAPS = {"slope": (("slopes", "azimuth_node"), ("slopes", "radial_node"), ("slopes", "slope_loop")),
        "hemisphere": (("hemimap", "azimuth"), ("hemimap", "node"), ("kernels", "hemisphere"))}
#: A skeleton: panels × azimuths × nodes.
DEPTH = 3

Helper = tuple[str, str]  # (module, function)


def _sources() -> dict[str, str]:
    return {path.stem: path.read_text(encoding="utf-8") for path in sorted(COMPILED.glob("*.py"))}


class _Module:
    """One module's top-level functions and how its names resolve to helpers of ``engine/compiled``."""

    def __init__(self, name: str, source: str, modules: set[str]) -> None:
        self.name = name
        tree = ast.parse(source)
        self.functions = {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}
        self.names: dict[str, Helper] = {n: (name, n) for n in self.functions}
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module:
                module = node.module.rsplit(".", 1)[-1]
                if module in modules:
                    self.names.update({alias.asname or alias.name: (module, alias.name) for alias in node.names})

    def calls(self, nodes: list[ast.stmt], loops: bool = False) -> set[Helper]:
        """The helpers called in ``nodes``; inside the loops nested in them too where ``loops``."""
        found: set[Helper] = set()
        stack = list(nodes)
        while stack:
            node = stack.pop()
            if isinstance(node, ast.For | ast.While) and not loops:
                stack.append(node.iter if isinstance(node, ast.For) else node.test)
                continue
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in self.names:
                found.add(self.names[node.func.id])
            stack.extend(ast.iter_child_nodes(node))
        return found


class Skeletons:
    """The loop nests of every top-level function of a set of ``engine/compiled`` sources."""

    def __init__(self, sources: dict[str, str]) -> None:
        self.modules = {name: _Module(name, source, set(sources)) for name, source in sources.items()}
        self._reach: dict[Helper, frozenset[Helper]] = {}

    def reach(self, helper: Helper) -> frozenset[Helper]:
        """``helper`` and every helper it calls, transitively."""
        if helper not in self._reach:
            self._reach[helper] = frozenset({helper})
            module = self.modules.get(helper[0])
            function = module.functions.get(helper[1]) if module else None
            if function is not None:
                found = {helper}
                for called in module.calls(function.body, loops=True):
                    found |= self.reach(called)
                self._reach[helper] = frozenset(found)
        return self._reach[helper]

    def nests(self, helper: Helper) -> list[tuple[frozenset[Helper], ...]]:
        """Every chain of nested loops of ``helper``, outermost first, each level the helpers it reaches."""
        module = self.modules[helper[0]]

        def chains(loop: ast.For | ast.While) -> list[tuple[frozenset[Helper], ...]]:
            level = frozenset().union(*(self.reach(h) for h in module.calls(loop.body)))
            return [(level, *rest) for child in _loops(loop.body) for rest in chains(child)] or [(level,)]

        return [chain for loop in _loops(module.functions[helper[1]].body) for chain in chains(loop)]

    def functions(self) -> list[Helper]:
        return [(m.name, f) for m in self.modules.values() for f in m.functions]

    def evaluating(self, azimuth: Helper, node: Helper) -> list[Helper]:
        """The functions with a loop (over panels) enclosing a level reaching ``azimuth`` that encloses one reaching
        ``node``. (A loop over one case's azimuths and nodes, as the fused global rule's grid fill, is not one.)"""
        found = []
        for function in self.functions():
            for chain in self.nests(function):
                outer = [i for i, level in enumerate(chain) if azimuth in level and i >= DEPTH - 2]
                if outer and any(node in level for level in chain[outer[0] + 1:]):
                    found.append(function)
                    break
        return found

    def shared(self) -> list[tuple[Helper, Helper]]:
        """Pairs of functions with a nest of DEPTH or more loops calling the same helpers level by level."""
        seen: dict[tuple[frozenset[Helper], ...], Helper] = {}
        pairs = []
        for function in self.functions():
            for chain in self.nests(function):
                key = tuple(level for level in chain if level)
                if len(chain) < DEPTH or len(key) < 2:
                    continue
                if key in seen and seen[key] != function:
                    pairs.append((seen[key], function))
                seen.setdefault(key, function)
        return pairs


def _loops(body: list[ast.stmt]) -> list[ast.For | ast.While]:
    """The outermost loops within ``body`` (at any depth of other statements)."""
    found, stack = [], list(body)
    while stack:
        node = stack.pop(0)
        if isinstance(node, ast.For | ast.While):
            found.append(node)
        else:
            stack.extend(n for n in ast.iter_child_nodes(node) if isinstance(n, ast.stmt))
    return found


@pytest.mark.parametrize("name", sorted(MAPS))
def test_one_function_loops_over_each_maps_panels_and_nodes(name):
    azimuth, node, owner = MAPS[name]
    assert Skeletons(_sources()).evaluating(azimuth, node) == [owner]


def test_no_two_kernels_share_a_loop_nest():
    assert Skeletons(_sources()).shared() == []


def _with_copy(module: str, function: str, copy: str, edit=lambda text: text) -> dict[str, str]:
    """The sources with ``function`` of ``module`` written again, ``edit``-ed, under the name ``copy``."""
    sources = _sources()
    node = next(n for n in ast.parse(sources[module]).body if isinstance(n, ast.FunctionDef) and n.name == function)
    text = ast.get_source_segment(sources[module], node).replace(f"def {function}(", f"def {copy}(", 1)
    sources[module] += "\n\n" + edit(text) + "\n"
    return sources


@pytest.mark.parametrize("name", sorted(MAPS))
def test_a_second_copy_of_a_skeleton_is_found(name):
    azimuth, node, (module, function) = MAPS[name]
    skeletons = Skeletons(_with_copy(module, function, "copied_loop"))
    assert skeletons.evaluating(azimuth, node) == [(module, function), (module, "copied_loop")]
    assert ((module, function), (module, "copied_loop")) in skeletons.shared()


def test_a_copy_that_calls_the_node_map_through_another_helper_is_found():
    # the slope loop again with a weight helper of its own (which reaches slope_node) in place of slope_node and the
    # value: the levels reach the same map (radial_node), so the copy shows
    def edit(text: str) -> str:
        start = text.index("s, weight_t, one_sp, n2, Lz = slope_node(")
        helper = "def node_weight(*args):\n    return slope_node(*args)\n\n\n"
        return helper + text[:start] + "node_weight(kind, v[r, j] - kind, start, length, out[r, i, j])\n"
    sources = _with_copy("slopes", "slope_loop", "copied_loop", edit)
    ast.parse(sources["slopes"])
    assert "slope_node(" not in sources["slopes"].rsplit("def copied_loop(", 1)[1]
    found = Skeletons(sources).evaluating(("slopes", "azimuth_node"), ("slopes", "radial_node"))
    assert found == [("slopes", "slope_loop"), ("slopes", "copied_loop")]
