"""What the unit and statistical tests share: the shard settings of the default config (a
support module, as workflow_support.py; tests/workflow has a conftest.py of its own).

The one home of the bins and shard settings the tests run with (import it as
``from default_settings import DEFAULT_SETTINGS``): a test that needs other settings replaces
them (``DEFAULT_SETTINGS.replace(shard_time=...)``) and keeps the rest.
"""

from workflow_support import REPOSITORY

from bouncing_ball.workflow.config import read_config, shard_settings

# config/config.yaml's settings at r = 1/2: its speed and position bins (P(0, v); P(x) and
# <v^2>_x), velocity and flight-time bins, criterion constant c and step rule
DEFAULT_SETTINGS = shard_settings(read_config(REPOSITORY / "config" / "config.yaml"), "0.5")
