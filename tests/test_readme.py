"""The README's Python example runs and gives walking-grade accuracy."""

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_example_runs(capsys):
    code = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)[0]
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)
    pct = namespace["error_m"] / namespace["truth"].distance_m[namespace["lanes"], namespace["end"]]
    assert pct.shape == (8,)
    # An industrial-grade foot IMU with ZUPTs over 1–3 min of walking: a few % of distance
    # (docs/ENV_FOOT.md: median 3.4 % over 24 walks for this grade; a walk with a long stop
    # drifts more under the paper's boundary-only ZUPTs). A broken filter gives ≫ 10 %.
    import numpy as np

    assert float(np.median(pct)) < 0.08
    assert float(pct.max()) < 0.5
    assert capsys.readouterr().out.strip().startswith("[")
