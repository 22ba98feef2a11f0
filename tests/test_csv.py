import warnings

import pytest

from handsynth._csv import column_index, read_rows, stream_rows
from handsynth.errors import RecordingError


def test_a_spreadsheet_export_is_read_as_it_comes(tmp_path):
    """Byte-order mark, ';' and decimal commas, quotes, CRLF, comments, empty rows."""
    p = tmp_path / "export.csv"
    p.write_bytes("\ufefftime_s;\"acc x\";label\r\n# a comment\r\n0;-1,5;\"a;b\"\r\n;;\r\n"
                  "0,01;2,25e-3;c\r\n".encode("utf-8"))
    got = read_rows(p)
    assert got.rows == [["time_s", "acc x", "label"], ["0", "-1.5", "a;b"], ["0.01", "2.25e-3", "c"]]
    assert got.lines == [1, 3, 5]
    assert got.delimiter == ";" and got.decimal_comma


def test_comma_and_tab_files(tmp_path):
    p = tmp_path / "plain.csv"
    p.write_text("a,b\n1.5,\"2\"\n")
    got = read_rows(p)
    assert got.rows == [["a", "b"], ["1.5", "2"]] and got.delimiter == "," and not got.decimal_comma
    t = tmp_path / "tabs.txt"
    t.write_text("a\tb\n1,5\t2\n")
    got = read_rows(t)
    assert got.rows == [["a", "b"], ["1.5", "2"]] and got.delimiter == "\t" and got.decimal_comma


def test_binary_and_missing_files_are_named(tmp_path):
    b = tmp_path / "rec.npy"
    b.write_bytes(b"\x93NUMPY\x01\x00\x00\x00")
    with pytest.raises(RecordingError, match=r"rec.npy: binary content; expected CSV text \(IMU recording\)"):
        read_rows(b, what="IMU recording")
    with pytest.raises(RecordingError, match="cannot read glove CSV .*missing.csv.*no such file"):
        read_rows(tmp_path / "missing.csv", what="glove CSV")


def test_space_separated_columns(tmp_path):
    p = tmp_path / "logger.txt"
    p.write_text("time  a   b\n0.0  1.5 -2\n0.1\t2.5 -3\n")
    got = read_rows(p)
    assert got.rows == [["time", "a", "b"], ["0.0", "1.5", "-2"], ["0.1", "2.5", "-3"]]
    assert got.delimiter == " " and not got.decimal_comma


def test_a_spreadsheets_sep_line_and_unicode_text(tmp_path):
    p = tmp_path / "excel.csv"
    p.write_text("sep=;\na;b\n1,5;2\n")
    got = read_rows(p)
    assert got.rows == [["a", "b"], ["1.5", "2"]] and got.lines == [2, 3] and got.delimiter == ";"
    u = tmp_path / "unicode.txt"  # a spreadsheet's "Unicode text": UTF-16 with tabs
    u.write_bytes("a\tb\r\n1,5\t2\r\n".encode("utf-16"))
    assert read_rows(u).rows == [["a", "b"], ["1.5", "2"]]


def test_a_column_named_twice_is_refused_by_name():
    assert column_index(["t", "a", "", "b"], path="x.csv") == {"t": 0, "a": 1, "b": 3}
    with pytest.raises(RecordingError, match=r"x.csv, line 4: column 'a' stands twice "
                                             r"\(columns 2 and 4\)"):
        column_index(["t", "a", "b", "a"], path="x.csv", line=4)


def test_a_last_line_without_line_end_is_left_out_with_a_warning(tmp_path):
    """A logger cut off while writing leaves its last number short (12.3 of 12.345)."""
    p = tmp_path / "cut.csv"
    p.write_text("t,a\n0,1.5\n0.01,12.3")
    with pytest.warns(UserWarning, match=r"cut.csv, line 3: the file ends without a line end"):
        got = read_rows(p)
    assert got.rows == [["t", "a"], ["0", "1.5"]] and got.lines == [1, 2]
    for whole in ("t,a\n0,1.5\n0.01,12.345\n", "t,a\r\n0,1.5\r\n", "t,a\n0,1.5\n# end"):
        p.write_text(whole)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            assert read_rows(p).rows[1] == ["0", "1.5"]
    p.write_text("t,a")  # one line alone is kept: the reader names what is missing
    assert read_rows(p).rows == [["t", "a"]]


def test_a_number_with_underscores_is_refused(tmp_path):
    p = tmp_path / "u.csv"
    p.write_text("t,a,note\n0,1_000,take_1\n")
    with pytest.raises(RecordingError, match=r"u.csv, line 2, column 2: '1_000' is not a number"):
        read_rows(p)
    p.write_text("t,a,note\n0,1000,take_1\n")
    assert read_rows(p).rows[1] == ["0", "1000", "take_1"]


def test_a_plain_number_table_reads_as_read_rows_reads_it_and_other_files_are_left_to_it(
        tmp_path):
    import numpy as np

    from handsynth._csv import read_number_table, read_rows

    plain = "t,a,b,note\n# a comment\n0,1.5,-2e-3,7\n\n0.01,2.5,3,8\n"
    path = tmp_path / "plain.csv"
    path.write_text(plain)
    got = read_number_table(path, what="test", usecols=lambda header, line: [2, 0])
    assert got is not None and got.header == ["t", "a", "b", "note"] and got.lines == [3, 5]
    rows = read_rows(path, what="test")
    want = np.array([[float(r[2]), float(r[0])] for r in rows.rows[1:]])
    np.testing.assert_array_equal(got.table, want)
    # what only read_rows reads (or refuses, naming it) is not read here
    for name, text in (("semicolon", "t;a\n0;1,5\n1;2,5\n"), ("quoted", 't,a\n"0",1\n1,2\n'),
                       ("sep", "sep=,\nt,a\n0,1\n1,2\n"), ("underscore", "t,a\n0,1_000\n1,2\n"),
                       ("ragged", "t,a\n0,1\n1,2,3\n"), ("open end", "t,a\n0,1\n1,2"),
                       ("empty row", "t,a\n0,1\n,\n1,2\n"), ("text", "t,a\n0,x\n1,2\n")):
        path = tmp_path / f"{name}.csv"
        path.write_text(text)
        assert read_number_table(path, what="test", usecols=lambda h, line: [0, 1]) is None, name


def test_names_are_replaced_by_what_they_mean_and_two_of_one_meaning_refused():
    from handsynth._csv import names_by_meaning

    meaning = {"Acc X": "acc_x", "acc_x": "acc_x", "accel-x": "acc_x"}.get
    header, renamed = names_by_meaning(["t", "Acc X", "note"], meaning, path="f.csv")
    assert header == ["t", "acc_x", "note"] and renamed == [("Acc X", "acc_x")]
    assert names_by_meaning(["acc_x"], meaning, path="f.csv") == (["acc_x"], [])
    with pytest.raises(RecordingError, match=r"^f.csv: columns 'acc_x' and 'accel-x' both read "
                                             r"as acc_x: which one holds the data is unknown$"):
        names_by_meaning(["acc_x", "accel-x"], meaning, path="f.csv")


def test_stream_rows_take_the_header_s_delimiter():
    lines = ["\ufeff# a logger's note", "", 'time_s;"a x";b', "0,5;1,25;-2", "# later", "1;2,5;"]
    assert list(stream_rows(lines)) == [(3, ["time_s", "a x", "b"]), (4, ["0.5", "1.25", "-2"]),
                                        (6, ["1", "2.5", ""])]
    assert list(stream_rows(["t\tx", "0.5\t1,5"])) == [(1, ["t", "x"]), (2, ["0.5", "1.5"])]
    # commas stay delimiters (decimal points) once the header has them
    assert list(stream_rows(["t,x;y", "1.5,2"])) == [(1, ["t", "x;y"]), (2, ["1.5", "2"])]
    assert list(stream_rows([])) == []
