"""Test-session settings shared by every test module.

Property tests (Hypothesis) draw the same examples on every run unless
``HYPOTHESIS_PROFILE=explore`` is set: a submission's CI must not pass or fail by the luck of
the draw (a random draw once found a corner case of a test's own set-up, not of the code).
Run ``HYPOTHESIS_PROFILE=explore python -m pytest tests`` now and then to search further.
"""

from __future__ import annotations

import os

from hypothesis import settings

settings.register_profile("repeatable", derandomize=True, database=None, deadline=None)
settings.register_profile("explore", deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))
