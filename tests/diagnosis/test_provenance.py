"""`reconstruction.json` beside the flights: read, reported beside the verdict, keys optional."""

import json

import pytest

import fwid
from fwid.diagnosis import read_reconstruction
from fwid.diagnosis._provenance import provenance, provenance_text


def _write(folder, flights):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "reconstruction.json").write_text(json.dumps({"flights": flights}))
    return folder


def test_each_file_gets_the_entry_of_its_own_folder(tmp_path):
    """Equal file names in two folders stay apart; a folder without the file, or a file the
    JSON does not name, gets none."""
    tr = _write(tmp_path / "train", [{"flight": "a.csv", "source": "motive",
                                      "clock_offset_s": -133.0, "dropouts": [[1.0, 1.5]],
                                      "warnings": []}])
    te = _write(tmp_path / "test", [{"flight": "a.csv", "gyro_residual_rms": 0.02}])
    got = read_reconstruction([tr / "a.csv", te / "a.csv", te / "b.csv", tmp_path / "c.csv"])
    assert got[0]["clock_offset_s"] == -133.0 and got[1] == {"flight": "a.csv",
                                                            "gyro_residual_rms": 0.02}
    assert got[2] is None and got[3] is None


def test_a_malformed_file_is_one_line_naming_it(tmp_path):
    (tmp_path / "reconstruction.json").write_text("{not json")
    with pytest.raises(fwid.InputError, match="reconstruction.json: not readable as JSON"):
        read_reconstruction([tmp_path / "a.csv"])
    (tmp_path / "reconstruction.json").write_text(json.dumps({"flights": [{"source": "x"}]}))
    with pytest.raises(fwid.InputError, match="Formats and interfaces"):
        read_reconstruction([tmp_path / "a.csv"])


def test_the_block_keeps_what_is_there_and_counts_dropouts():
    entries = [{"flight": "a.csv", "clock_offset_s": -1.5,
                "dropouts": [[1.0, 1.25], [2.0, 2.5]], "warnings": ["gap"],
                "gyro_residual_rms": 0.03},
               {"flight": "b.csv"},  # only the name: every other key missing
               None]
    block = provenance(["a.csv", "b.csv", "c.csv"], entries)
    assert block["reconstructed"] == "some" and block["missing"] == ["c.csv"]
    a, b = block["flights"]
    assert a["dropouts"] == 2 and a["dropout_s"] == pytest.approx(0.75)
    assert a["gyro_residual_rms"] == 0.03 and b == {"flight": "b.csv"}
    text = provenance_text(block)
    assert text.startswith("2 of 3 flights rebuilt from raw recordings by fwid reconstruct")
    assert "clock offset -1.500 s" in text
    assert "tracking dropouts in 1 flight (0.75 s in all)" in text
    assert "warnings on a.csv" in text and "gyro_residual_rms 0.03" in text
    assert "to 0.03" not in text
    assert provenance(["a.csv", "b.csv"], entries[:2])["reconstructed"] == "all"
    none = provenance(["x.csv"], None)
    assert none["reconstructed"] == "none" and provenance_text(none) is None
    with pytest.raises(fwid.InputError, match="one entry"):
        provenance(["a.csv"], entries)
