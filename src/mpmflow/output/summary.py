"""summary.json: status, counts, timings and the fully resolved case."""

import json
from collections.abc import Mapping
from pathlib import Path

from .atomic import write_text


def write_summary(path: str | Path, summary: Mapping[str, object]) -> None:
    write_text(path, json.dumps(summary, indent=2, sort_keys=False) + "\n")
