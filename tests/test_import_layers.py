"""Imports run one way, gait → sensors → nav → envs → baselines → agents (io, replay,
reproduce, calibration and testing are side packages; seeds and sb3 sit beside envs), and
no module imports another's ``_private`` — nor does a test (tests use the public API)."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NAV = {"checks", "constants", "draws", "files", "rotations", "gait", "sensors", "nav"}
ENVS = NAV | {"io", "replay", "envs", "seeds", "pednav_env"}  # pednav_env: the registering __init__
#: What each unit (a pednav_env subpackage or module, baselines, agents) may import.
MAY_IMPORT = {
    "checks": set(),
    "files": set(),
    "constants": set(),
    "rotations": set(),
    "draws": set(),
    "seeds": set(),
    "gait": {"checks", "constants", "draws", "rotations", "gait"},
    "sensors": NAV - {"nav"},
    "nav": NAV,
    "io": {"checks", "constants", "rotations", "sensors", "io"},
    "replay": NAV | {"io", "replay"},
    "reproduce": NAV | {"reproduce"},
    "calibration": NAV | {"io", "calibration"},
    "envs": ENVS,
    "pednav_env": ENVS,
    "sb3": ENVS | {"sb3"},
    "testing": ENVS | {"reproduce", "testing"},
    "baselines": ENVS | {"baselines"},
    "agents": ENVS | {"reproduce", "testing", "baselines", "calibration", "sb3", "agents"},
}
#: Violations on main today: (importer, imported module or private name). Each entry
#: goes once the code is back in its layer (the test fails on a stale entry).
KNOWN: set[tuple[str, str]] = set()


def unit(name: str) -> str | None:
    """The unit of a dotted name: pednav_env.nav.ukf → nav, agents.cli → agents; None
    outside the project."""
    top, *rest = name.split(".")
    if (
        top == "pednav_env"
        and rest
        and any((ROOT / top / rest[0]).with_suffix(s).exists() for s in ("", ".py"))
    ):
        return rest[0]  # a subpackage or module: a new one must be given a row in MAY_IMPORT
    return top if top in ("pednav_env", "baselines", "agents") else None


def private_imports(path: Path) -> list[str]:
    """Private names (``_x``, not dunders) that ``path`` imports from the project."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            full = [f"{node.module}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            full = [a.name for a in node.names]
        else:
            continue
        for name in full:
            if unit(name) is None:
                continue
            if any(p.startswith("_") and not p.endswith("__") for p in name.split(".")):
                found.append(name)
    return found


def test_tests_import_no_private_names_of_the_project():
    found = {
        str(path.relative_to(ROOT)): names
        for path in (ROOT / "tests").rglob("*.py")
        if (names := private_imports(path))
    }
    assert not found, f"tests importing private names (use the public API): {found}"


def test_imports_follow_the_layers_and_leave_private_names_alone():
    found = set()
    paths = [p for pkg in ("pednav_env", "baselines", "agents") for p in (ROOT / pkg).rglob("*.py")]
    for path in paths:
        src = ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                assert node.level == 0, f"{src}: use absolute imports"
                names = [(node.module, f"{node.module}.{a.name}") for a in node.names]
            elif isinstance(node, ast.Import):
                names = [(a.name, a.name) for a in node.names]
            else:
                continue
            for module, full in names:  # full: module.name for `from module import name`
                if unit(full) is None:
                    continue  # the standard library or a third-party package
                if unit(full) not in MAY_IMPORT[unit(src)]:
                    found.add((src, module if unit(module) == unit(full) else full))
                if full.split(".")[-1].startswith("_") and not full.endswith("__"):
                    found.add((src, full))
    new, fixed = sorted(found - KNOWN), sorted(KNOWN - found)
    assert not new, f"imports against the layers, or of another module's private names: {new}"
    assert not fixed, f"fixed: remove these entries from KNOWN: {fixed}"
