"""The docs stand alone: every file they (and the code and --help) point to exists, and
the script of docs/TRAIN_YOUR_OWN.md runs."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: Folders that are not the project's own text (environments, outputs, caches).
SKIPPED = {".venv", ".git", "runs", "build", "__pycache__", ".ruff_cache", ".pytest_cache"}
#: Top-level folders of the repository: a path mention starting with one must resolve.
TOP = {"agents", "baselines", "pednav_env", "docs", "tests", "benchmarks"}
#: A path-like mention ending in a file extension: docs/X.md, agents/evaluate.py, …
PATH_MENTION = re.compile(
    r"(?<![\w./-])((?:[\w.-]+/)*[\w.-]+\.(?:md|py|json|ya?ml|png|csv|mat|pkl|zip|txt|toml))"
    r"(?![\w/])"
)
#: Markdown link targets: [text](target)
LINK = re.compile(r"\]\(([^)\s]+)\)")
#: Not checked: history names files that have since moved; this file names missing ones
#: on purpose.
UNCHECKED = {"CHANGELOG.md", "test_docs.py"}
#: Files of other projects that the text names (they are not in this repository).
EXTERNAL = {"tests/envs/test_envs.py"}  # Gymnasium's env tests


def project_files() -> list[Path]:
    out = []
    for path in ROOT.rglob("*"):
        rel = path.relative_to(ROOT)
        if set(rel.parts) & SKIPPED or rel.parts[0].endswith(".egg-info"):
            continue
        if path.is_file() and (path.suffix in (".md", ".py", ".toml") or path.name == "Makefile"):
            out.append(path)
    return out


def dangling(text: str, where: Path) -> list[str]:
    """Mentions in ``text`` (of the file ``where``) that resolve to no file."""
    bad = []
    for match in PATH_MENTION.finditer(text):
        ref = match.group(1)
        if "/" in ref:
            if ref.split("/")[0] not in TOP:
                continue  # a path outside the repository, e.g. runs/… or ../shared/…
        elif not ref.endswith(".md"):
            continue  # a bare file name such as model.zip
        if ref not in EXTERNAL and not ((ROOT / ref).exists() or (where.parent / ref).exists()):
            bad.append(ref)
    if where.suffix == ".md":
        for match in LINK.finditer(text):
            target = match.group(1).split("#")[0]
            external = re.match(r"^[a-z]+:", target)
            if target and not external and not (where.parent / target).exists():
                bad.append(f"link {target}")
    return bad


def help_texts() -> str:
    from agents.cli import build_parser

    parser = build_parser()
    texts = [parser.format_help()]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            texts += [sub.format_help() for sub in action.choices.values()]
    return "\n".join(texts)


def test_the_checker_catches_a_dangling_reference(tmp_path):
    doc = ROOT / "docs" / "X.md"  # (not written: only its folder matters)
    text = "See DESIGN.md, docs/NOPE.md, [a](NOPE.md) and docs/CONTRACTS.md."
    assert dangling(text, doc) == ["DESIGN.md", "docs/NOPE.md", "NOPE.md", "link NOPE.md"]


def test_no_dangling_reference_in_docs_code_or_help():
    """Every relative link and every repository path mentioned in a .md file, a module
    (docstrings, comments, strings) or a --help text names a file that exists."""
    bad = []
    for path in project_files():
        if path.name in UNCHECKED:
            continue
        bad += [f"{path.relative_to(ROOT)}: {ref}" for ref in dangling(path.read_text(), path)]
    bad += [f"--help: {ref}" for ref in dangling(help_texts(), ROOT / "help.txt")]
    assert not bad, "\n".join(bad)


def test_train_your_own_script_runs(tmp_path, monkeypatch, capsys):
    """The python blocks of docs/TRAIN_YOUR_OWN.md, in order, with a small budget."""
    text = (ROOT / "docs" / "TRAIN_YOUR_OWN.md").read_text()
    code = "\n".join(re.findall(r"```python\n(.*?)```", text, flags=re.S))
    small = {"TIMESTEPS": "2048", "EPISODES": "3"}  # one PPO update; three episodes
    for name, value in small.items():
        code, n = re.subn(rf"^{name} = .*$", f"{name} = {value}", code, flags=re.M)
        assert n == 1, name
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "TRAIN_YOUR_OWN.md", "exec"), {"__name__": "__doc_example__"})
    out = capsys.readouterr().out
    assert (tmp_path / "runs" / "my_ppo" / "vecnormalize.pkl").exists()
    assert "pednav/WaistStep-v0: 3 episodes" in out and "runs/my_ppo" in out
    assert re.search(r"PPO: mean time-averaged error \d+\.\d{3} m over 3 episodes", out)


@pytest.mark.parametrize(
    "page", ["ARCHITECTURE.md", "CONTRACTS.md", "CONVENTIONS.md", "TRAIN_YOUR_OWN.md"]
)
def test_new_pages_are_listed_in_the_readme(page):
    assert f"docs/{page}" in (ROOT / "README.md").read_text()
