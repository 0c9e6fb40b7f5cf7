"""Regenerate the case-file reference table in README.md from the schema.

    python scripts/update_readme_reference.py
"""

from pathlib import Path

from mpmflow.case import reference_markdown

README = Path(__file__).resolve().parents[1] / "README.md"
START, END = "<!-- case-reference:start -->\n", "\n<!-- case-reference:end -->"

text = README.read_text()
head, rest = text.split(START, 1)
tail = rest.split(END, 1)[1]
README.write_text(head + START + reference_markdown() + END + tail)
print(f"updated {README}")
