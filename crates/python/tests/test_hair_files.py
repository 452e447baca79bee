"""coiffure.read_hair / write_hair: every format by extension, round trips and errors with offsets."""

from __future__ import annotations

import numpy as np
import pytest

import coiffure

FORMATS = [".hair", ".data", ".tfx", ".usda"]


def strands(n: int = 7, points: int = 16, seed: int = 3) -> list[np.ndarray]:
    """Random-walk strands in metres (equal point counts, as .tfx needs)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        root = rng.normal(scale=0.1, size=3)
        steps = rng.normal(scale=0.004, size=(points - 1, 3)) + [0.0, 0.0, -0.01]
        out.append(np.vstack([root, root + np.cumsum(steps, axis=0)]))
    return out


@pytest.mark.parametrize("ext", FORMATS)
def test_round_trip_is_exact_in_float32(tmp_path, ext):
    data = strands()
    path = tmp_path / f"tress{ext}"
    coiffure.write_hair(path, data)
    back = coiffure.read_hair(path)
    assert len(back) == len(data)
    for a, b in zip(data, back):
        assert b.dtype == np.float32 and b.shape == a.shape
        # Files hold float32: the values read are the written ones rounded to float32, exactly.
        assert np.array_equal(b, a.astype(np.float32))
    # Writing what was read gives the same bytes.
    again = tmp_path / f"again{ext}"
    coiffure.write_hair(again, back)
    assert again.read_bytes() == path.read_bytes()


@pytest.mark.parametrize("ext", [".hair", ".data", ".usda"])
def test_unequal_strands_and_empty_files(tmp_path, ext):
    data = [np.zeros((2, 3)), np.ones((5, 3)), np.full((1, 3), 0.5)]
    coiffure.write_hair(tmp_path / f"a{ext}", data)
    back = coiffure.read_hair(tmp_path / f"a{ext}")
    assert [len(s) for s in back] == [2, 5, 1]
    assert np.array_equal(back[1], np.ones((5, 3), np.float32))
    coiffure.write_hair(tmp_path / f"empty{ext}", [])
    assert coiffure.read_hair(tmp_path / f"empty{ext}") == []


def test_conversion_between_formats_keeps_the_points(tmp_path):
    data = strands(points=8)
    coiffure.write_hair(tmp_path / "a.tfx", data)
    for ext in [".hair", ".data", ".usda"]:
        coiffure.write_hair(tmp_path / f"b{ext}", coiffure.read_hair(tmp_path / "a.tfx"))
        for a, b in zip(coiffure.read_hair(tmp_path / f"b{ext}"), data):
            assert np.array_equal(a, b.astype(np.float32))


@pytest.mark.parametrize("ext", [".hair", ".data", ".tfx"])
def test_truncated_binary_file_names_the_byte_offset(tmp_path, ext):
    path = tmp_path / f"t{ext}"
    coiffure.write_hair(path, strands())
    raw = path.read_bytes()
    cut = tmp_path / f"cut{ext}"
    cut.write_bytes(raw[: len(raw) - 5])
    with pytest.raises(ValueError, match=r"byte \d+") as e:
        coiffure.read_hair(cut)
    assert str(cut) in str(e.value)


def test_malformed_usda_names_the_line(tmp_path):
    path = tmp_path / "bad.usda"
    coiffure.write_hair(path, strands(n=2, points=4))
    lines = path.read_text().splitlines()
    i = next(k for k, l in enumerate(lines) if "points" in l)
    lines[i] = lines[i].replace("(", "(oops ", 1)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=rf"line {i + 1}\b"):
        coiffure.read_hair(path)


def test_unwritable_data_and_bad_names(tmp_path):
    with pytest.raises(ValueError, match="same number of vertices"):
        coiffure.write_hair(tmp_path / "x.tfx", [np.zeros((4, 3)), np.zeros((5, 3))])
    assert not (tmp_path / "x.tfx").exists()
    with pytest.raises(ValueError, match="extension"):
        coiffure.write_hair(tmp_path / "x.obj", strands())
    with pytest.raises(ValueError, match="shape"):
        coiffure.write_hair(tmp_path / "x.hair", [np.zeros((4, 2))])
    with pytest.raises(ValueError, match="finite"):
        coiffure.write_hair(tmp_path / "x.hair", [np.full((4, 3), np.nan)])
    with pytest.raises(FileNotFoundError):
        coiffure.read_hair(tmp_path / "missing.hair")
