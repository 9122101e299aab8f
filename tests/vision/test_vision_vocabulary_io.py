"""Round trips through the native binary format and DBoW2's text format; corrupt files."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from symloc.errors import VocabularyFileError
from symloc.vision.bow import Scoring, Weighting
from symloc.vision.vocabulary import (
    Vocabulary,
    load_dbow2_text,
    load_vocabulary,
    save_dbow2_text,
    save_vocabulary,
)
from symloc.vision.vocabulary_io import HEADER_SIZE


@pytest.fixture(scope="module")
def voc() -> Vocabulary:
    rng = np.random.default_rng(0)
    docs = [rng.integers(0, 256, (60, 32), dtype=np.uint8) for _ in range(5)]
    return Vocabulary.train(docs, k=3, L=3, weighting="tf-idf", scoring="l1", rng=0, progress=False)


@pytest.mark.parametrize("compress", [False, True])
def test_native_round_trip(voc: Vocabulary, tmp_path, compress: bool) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "voc.bin"
    save_vocabulary(voc, path, compress=compress)
    back = load_vocabulary(path)
    assert back.equals(voc)
    d = np.random.default_rng(1).integers(0, 256, (40, 32), dtype=np.uint8)
    a, b = voc.transform(d)[0], back.transform(d)[0]
    assert np.array_equal(a.words, b.words)
    assert np.array_equal(a.values, b.values)


def test_dbow2_text_round_trip(voc: Vocabulary, tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "voc.txt"
    voc.save_dbow2_text(path)
    first = path.read_text().splitlines()[0]
    assert first.split() == ["3", "3", "0", "0"]  # k L scoring weighting
    back = load_dbow2_text(path)
    assert back.equals(voc)
    assert load_vocabulary(path).equals(voc)  # detected by content
    # text -> native -> text gives the same file
    save_vocabulary(back, tmp_path / "v.bin")
    save_dbow2_text(load_vocabulary(tmp_path / "v.bin"), tmp_path / "v2.txt")
    assert (tmp_path / "v2.txt").read_text() == path.read_text()


def test_reads_orbvoc_style_text(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # ORBvoc.txt layout: "10 6  0 0" header, double spaces, trailing blank line, 6-digit weights
    d0 = " ".join(["0"] * 32)
    d1 = " ".join(["255"] * 32)
    text = f"2 1  1 3\n0 1 {d0}  0.693147\n0 1 {d1}  1.38629\n\n"
    p = tmp_path / "ORBvoc.txt"
    p.write_text(text)
    v = Vocabulary.load_dbow2_text(p)
    assert v.k == 2
    assert v.L == 1
    assert v.scoring is Scoring.L2_NORM
    assert v.weighting is Weighting.BINARY
    assert v.word_weights().tolist() == [0.693147, 1.38629]


def _text(lines: list[str]) -> str:
    return "\n".join(lines) + "\n"


GOOD = "0 1 " + " ".join(["7"] * 32) + " 0.5"


@pytest.mark.parametrize(
    ("lines", "match"),
    [
        (["10 6 0"], "line 1: expected header"),
        (["10 x 0 0"], "line 1: header values must be integers"),
        (["10 6 9 0"], "line 1: header out of range"),
        (["2 1 0 0", GOOD, "0 1 1 2 3"], "line 3: expected 35 values"),
        (["2 1 0 0", GOOD, GOOD.replace(" 7 ", " abc ", 1)], "line 3: non-numeric"),
        (["2 1 0 0", GOOD, GOOD.replace(" 7 ", " 300 ", 1)], "line 3: descriptor bytes"),
        (["2 1 0 0", GOOD.replace("0 1", "5 1", 1)], "line 2: parent must be an earlier node"),
        (["2 1 0 0", GOOD.replace("0 1", "0 2", 1)], "line 2: isLeaf must be 0 or 1"),
        (
            ["2 2 0 0", GOOD, GOOD.replace("0 1", "1 1", 1)],
            "line 2: node is flagged as leaf but has children",
        ),
        (["2 1 0 0", GOOD.replace(" 0.5", " nan")], "line 2: weight must be finite"),
    ],
)
def test_text_errors_name_the_line(tmp_path, lines: list[str], match: str) -> None:  # type: ignore[no-untyped-def]
    p = tmp_path / "bad.txt"
    p.write_text(_text(lines))
    with pytest.raises(VocabularyFileError, match=match):
        load_dbow2_text(p)


def test_truncated_text_file(voc: Vocabulary, tmp_path) -> None:  # type: ignore[no-untyped-def]
    p = tmp_path / "voc.txt"
    voc.save_dbow2_text(p)
    data = p.read_text()
    cut = data[: len(data) // 2]  # ends mid-line
    p.write_text(cut)
    n_line = cut.count("\n") + 1
    with pytest.raises(VocabularyFileError, match=f"line {n_line}: expected 35 values"):
        load_dbow2_text(p)


def test_native_truncated_and_corrupt(voc: Vocabulary, tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "voc.bin"
    save_vocabulary(voc, path)
    data = path.read_bytes()
    (tmp_path / "t.bin").write_bytes(data[:-10])
    with pytest.raises(
        VocabularyFileError, match=r"byte \d+: payload is \d+ bytes, header says \d+ \(truncated\)"
    ):
        load_vocabulary(tmp_path / "t.bin")
    (tmp_path / "h.bin").write_bytes(data[:30])
    with pytest.raises(VocabularyFileError, match="byte 30: truncated header"):
        load_vocabulary(tmp_path / "h.bin")
    flipped = bytearray(data)
    flipped[HEADER_SIZE + 100] ^= 0xFF
    (tmp_path / "c.bin").write_bytes(bytes(flipped))
    with pytest.raises(VocabularyFileError, match="checksum mismatch"):
        load_vocabulary(tmp_path / "c.bin")
    newer = bytearray(data)
    newer[8:12] = struct.pack("<I", 99)
    (tmp_path / "v.bin").write_bytes(bytes(newer))
    with pytest.raises(VocabularyFileError, match="byte 8: format version 99"):
        load_vocabulary(tmp_path / "v.bin")
    badk = bytearray(data)
    badk[12:16] = struct.pack("<I", 1)
    (tmp_path / "k.bin").write_bytes(bytes(badk))
    with pytest.raises(VocabularyFileError, match="byte 12: invalid k 1"):
        load_vocabulary(tmp_path / "k.bin")
    (tmp_path / "x.bin").write_bytes(b"\x89PNG not a vocabulary")
    with pytest.raises(VocabularyFileError, match="byte 0: not a symloc vocabulary"):
        load_vocabulary(tmp_path / "x.bin")
    with pytest.raises(VocabularyFileError, match="cannot read"):
        load_vocabulary(tmp_path / "missing.bin")


def test_native_bad_parent_names_its_byte(tmp_path) -> None:  # type: ignore[no-untyped-def]
    import zlib

    v = Vocabulary(2, 1, 0, 0, [-1, 0, 0], np.zeros((3, 32), np.uint8), [0.0, 1.0, 1.0])
    path = tmp_path / "p.bin"
    save_vocabulary(v, path)
    data = bytearray(path.read_bytes())
    n = 3
    off = HEADER_SIZE + 8 * n + 4 * 2  # parent of node 2
    data[off : off + 4] = struct.pack("<i", 7)
    data[44:48] = struct.pack("<I", zlib.crc32(bytes(data[HEADER_SIZE:])) & 0xFFFFFFFF)
    path.write_bytes(bytes(data))
    with pytest.raises(VocabularyFileError, match=f"byte {off}: node 2 has parent 7"):
        load_vocabulary(path)


def test_convert_command(voc: Vocabulary, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from symloc.vision.vocabulary import main

    voc.save_dbow2_text(tmp_path / "a.txt")
    assert main([str(tmp_path / "a.txt"), str(tmp_path / "b.symvoc"), "--compress"]) == 0
    assert main([str(tmp_path / "b.symvoc"), str(tmp_path / "c.txt")]) == 0
    assert load_vocabulary(tmp_path / "c.txt").equals(voc)


def test_compressed_payload_that_does_not_inflate(voc: Vocabulary, tmp_path) -> None:  # type: ignore[no-untyped-def]
    import zlib

    path = tmp_path / "z.bin"
    save_vocabulary(voc, path, compress=True)
    data = bytearray(path.read_bytes())
    data[HEADER_SIZE + 8 : HEADER_SIZE + 12] = b"\x00\x01\x02\x03"  # break the zlib stream
    data[44:48] = struct.pack("<I", zlib.crc32(bytes(data[HEADER_SIZE:])) & 0xFFFFFFFF)
    path.write_bytes(bytes(data))
    with pytest.raises(VocabularyFileError, match="byte 64: cannot decompress weights and parents"):
        load_vocabulary(path)


def test_text_fast_and_fallback_parsers_agree(tmp_path) -> None:  # type: ignore[no-untyped-def]
    d0 = " ".join(["07"] * 32)  # leading zeros: still integers
    d1 = " ".join(["+9"] * 32)  # a sign: the vectorised parser hands over to the slower one
    lines = ["2 1  0 0", f"0 1 {d0}  1e-3", f"0 1 {d0}  2.5E+00"]
    (tmp_path / "a.txt").write_text("\n".join(lines) + "\n")
    (tmp_path / "b.txt").write_text("\n".join([*lines[:2], f"0 1 {d1}  2.5"]) + "\n")
    a = load_dbow2_text(tmp_path / "a.txt")
    b = load_dbow2_text(tmp_path / "b.txt")
    assert a.word_weights().tolist() == [0.001, 2.5]
    assert b.word_weights().tolist() == [0.001, 2.5]
    assert a.descriptors[1:].tolist() == [[7] * 32, [7] * 32]
    assert b.descriptors[2].tolist() == [9] * 32
