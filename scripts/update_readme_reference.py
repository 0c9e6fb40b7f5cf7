"""Regenerate the case-file reference, docs/reference.md, from the schema (mpmflow.case).

python scripts/update_readme_reference.py
"""

from pathlib import Path

from mpmflow.case import reference_page

PAGE = Path(__file__).resolve().parents[1] / "docs" / "reference.md"

PAGE.write_text(reference_page())
print(f"updated {PAGE}")
