"""Damaged record files (Parquet, CSV, SIDPAC .mat), made in the test: each is refused
with exit 2 and a message naming the file and, where it can be located, the column and
the rows; a damaged file is never read as a record."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import scipy.io

from flightid.record import read


@pytest.fixture(scope="module")
def parquet_bytes(flight_file) -> bytes:
    return flight_file.read_bytes()


def damaged(data: bytes, how: str, seed: int) -> bytes:
    rng = np.random.default_rng(seed)
    b = bytearray(data)
    if how == "head":
        return bytes(b[200 + 37 * seed:])
    if how == "tail":
        return bytes(b[: len(b) - 300 - 37 * seed])
    if how == "flipped":
        for i in rng.integers(0, len(b), 40):
            b[i] ^= 0xFF
        return bytes(b)
    if how == "zeroed":  # 200 zeroed bytes inside the file
        at = int(rng.integers(1000, len(b) - 2000))
        b[at:at + 200] = bytes(200)
        return bytes(b)
    raise AssertionError(how)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("how", ["head", "tail", "flipped", "zeroed"])
def test_damaged_parquet(cli, tmp_path, parquet_bytes, how, seed):
    path = tmp_path / "damaged.parquet"
    path.write_bytes(damaged(parquet_bytes, how, seed))
    result = cli(["identify", path], 2, str(path))
    assert any(w in result.output for w in ("not a readable Parquet record", "checksum",
                                            "not finite", "does not increase")), result.output


def test_zeroed_bytes_name_the_column(tmp_path, parquet_bytes):
    # damage well inside the data pages: the page checksum finds it and the reader names
    # the column chunk (the "200 zeroed bytes are accepted")
    data = bytearray(parquet_bytes)
    data[len(data) // 3:len(data) // 3 + 200] = bytes(200)
    path = tmp_path / "zeroed.parquet"
    path.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=r"column '\w+' rows \d+-\d+"):
        read(path)


def test_changed_values_fail_the_block_checksum(tmp_path, flight_file):
    # a file rewritten without page checksums but with one changed value: the flightid
    # block checksums name the column and the rows
    table = pq.read_table(flight_file)
    frame = table.to_pandas()
    frame.loc[300, "q"] += 1e-9
    edited = pa.Table.from_pandas(frame, preserve_index=False).replace_schema_metadata(
        table.schema.metadata)
    path = tmp_path / "edited.parquet"
    pq.write_table(edited, path)
    with pytest.raises(ValueError, match=r"column 'q' rows 0-\d+ do not match their checksum"):
        read(path)


@pytest.mark.parametrize("content, expected", [
    (b"", "not a readable Parquet record"),
    (b"not a parquet file at all", "not a readable Parquet record"),
    (b"PAR1" + bytes(64) + b"PAR1", "not a readable Parquet record"),
])
def test_not_parquet(cli, tmp_path, content, expected):
    path = tmp_path / "x.parquet"
    path.write_bytes(content)
    cli(["identify", path], 2, expected)


def write_csv(flight, path, edit=None):
    frame = flight.to_frame()
    if edit:
        frame = edit(frame)
    frame.to_csv(path, index=False)
    return path


@pytest.mark.parametrize("edit, expected", [
    (lambda f: f.assign(q=f.q.where((f.index < 40) | (f.index > 44))),
     "column 'q' has values that are not finite (NaN or infinite) in rows 40-44"),
    (lambda f: f.assign(p=f.p.where(f.index != 7, np.inf)), "column 'p'"),
    (lambda f: f.assign(time=f.time.where(f.index != 100, 0.5)), "column 'time' does not "
                                                                  "increase"),
    (lambda f: f.drop(columns="time"), "no 'time' column"),
    (lambda f: f.astype({"r": object}).assign(r=lambda g: g.r.where(g.index != 3, "abc")),
     "column 'r' has values that are not numbers in row 3"),
    (lambda f: f.iloc[:0], "no rows"),
])
def test_damaged_csv(cli, tmp_path, flight, edit, expected):
    path = write_csv(flight, tmp_path / "x.csv", edit)
    cli(["identify", path], 2, expected)


def test_csv_joined_with_itself_is_a_time_reversal(cli, tmp_path, flight):
    path = write_csv(flight, tmp_path / "twice.csv")
    text = path.read_text().splitlines()
    path.write_text("\n".join(text + text[1:]) + "\n")
    cli(["identify", path], 2, "column 'time' does not increase", "joined")


def test_csv_binary_garbage(cli, tmp_path):
    path = tmp_path / "x.csv"
    path.write_bytes(bytes(range(256)) * 4)
    cli(["identify", path], 2, "x.csv")


def test_csv_damaged_metadata_line(cli, tmp_path, flight):
    path = flight.write(tmp_path / "meta.csv")
    lines = path.read_text().splitlines()
    lines[0] = lines[0][:40]
    path.write_text("\n".join(lines) + "\n")
    cli(["identify", path], 2, "metadata is damaged")


def sidpac_file(path, fdata=None, t=None, **extra):
    n = 50
    t = np.arange(n) * 0.02 if t is None else t
    fdata = np.ones((n, 90)) if fdata is None else fdata
    scipy.io.savemat(path, {"fdata": fdata, "t": t, **extra})
    return path


@pytest.mark.parametrize("make, expected", [
    (lambda p: p.write_bytes(b"MATLAB garbage"), "not a readable MATLAB .mat file"),
    (lambda p: scipy.io.savemat(p, {"x": np.ones(3)}), "variable 'fdata' is missing"),
    (lambda p: sidpac_file(p, fdata=np.ones((50, 10))), "SIDPAC fdata has 90 columns"),
    (lambda p: sidpac_file(p, t=np.arange(40) * 0.02), "fdata has 50 rows but t has 40"),
    (lambda p: sidpac_file(p, fdata=np.where(np.arange(50)[:, None] == 9, np.nan,
                                             np.ones((50, 90)))), "not finite"),
    (lambda p: sidpac_file(p, t=np.r_[np.arange(25), np.arange(25)] * 0.02),
     "column 'time' does not increase in row 24"),
])
def test_damaged_sidpac(cli, tmp_path, make, expected):
    path = tmp_path / "flight.mat"
    make(path)
    cli(["identify", path], 2, expected)


@pytest.mark.parametrize("name, expected", [
    ("no/such/flight.parquet", "no such file"),
    ("flight.txt", "unknown record format '.txt'"),
    ("folder.parquet", "folder"),
])
def test_missing_or_unknown_files(cli, tmp_path, monkeypatch, name, expected):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "flight.txt").write_text("t,q\n0,1\n")
    (tmp_path / "folder.parquet").mkdir()
    cli(["identify", name], 2, expected)
