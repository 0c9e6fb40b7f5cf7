"""Writers for run outputs: time series (CSV), particle snapshots (VTU + PVD), summary (JSON).

Every file is written atomically (to a temporary file in the same folder, then renamed),
so a run that is killed never leaves a half-written output behind.
"""

from pathlib import Path

from ..errors import CaseError


def check_out_dir(out: str | Path, create: bool = True, name: str = "--out") -> None:
    """CaseError when the output folder ``out`` (``name`` in messages: the option or
    argument that gave it) is a file or (with ``create``) cannot be created."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise CaseError(f"{name} {out} exists and is not a folder; give a folder path.")
    if create:
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise CaseError(
                f"{name} {out} cannot be created: {err.strerror}. Give a folder you can write to."
            ) from None
