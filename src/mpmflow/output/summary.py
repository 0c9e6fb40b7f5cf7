"""summary.json: status, counts, timings and the fully resolved case."""

import json

from .atomic import write_text


def write_summary(path, summary):
    write_text(path, json.dumps(summary, indent=2, sort_keys=False) + "\n")
