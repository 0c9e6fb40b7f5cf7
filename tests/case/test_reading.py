"""Case files as they come (issue 40): one that starts with a UTF-8 byte-order mark is
read, and a case in a folder whose name is not UTF-8 runs (its mesh path, made absolute,
was refused as "changed after loading" when the run validated the case again)."""

import os
import shutil

from conftest import EXAMPLES, TINY_CASE

from mpmflow import load_case
from mpmflow.cli import main

MESH_CASE = """
[domain]
size = [0.3, 0.3, 0.3]
[grid]
spacing = 0.02
[[bodies]]
type = "mesh"
path = "geometry/blob.stl"
translate = [0.15, 0.15, 0.15]
[time]
dt = 1e-3
end = 2e-3
[output]
interval = 1e-3
snapshots = false
"""


def test_a_byte_order_mark_is_read_as_the_start_of_the_text(tmp_path, capsys):
    path = tmp_path / "case.toml"
    path.write_bytes(b"\xef\xbb\xbf" + TINY_CASE.encode())
    assert load_case(path).grid.spacing == 0.02
    assert main(["run", str(path), "--out", str(tmp_path / "o"), "-q"]) == 0
    assert "Traceback" not in capsys.readouterr().err


def test_a_case_in_a_folder_whose_name_is_not_utf8_runs(tmp_path, capsys):
    folder = tmp_path / os.fsdecode(b"case \xff\xfe")  # Latin-1 bytes, not UTF-8
    (folder / "geometry").mkdir(parents=True)
    shutil.copy(EXAMPLES / "geometry" / "blob.stl", folder / "geometry")
    path = folder / "case.toml"
    path.write_text(MESH_CASE)
    code = main(["run", str(path), "--out", str(folder / "out"), "-q"])
    err = capsys.readouterr().err
    assert code == 0 and "changed after loading" not in err and "Traceback" not in err
    assert load_case(path).bodies[0].path == str(folder / "geometry" / "blob.stl")
