"""Physical constants shared by every model (SI units)."""

from __future__ import annotations

#: Standard gravity g₀ (m/s²), the project's default (docs/CONVENTIONS.md); papers
#: 000/003/004 use it as "the normal value of gravity". Models take ``g`` as a parameter.
STANDARD_GRAVITY = 9.80665

#: Mean Earth radius (m) for the Schuler loop of papers 000/004.
EARTH_RADIUS = 6_371_000.0
