"""A sweep's rows file: whole rows only, torn and corrupt lines set aside with their bytes, a line per row."""
import json

import pytest

from closed_loop.batch import rows_file
from closed_loop.batch.sweep_file import SweepError

COLUMNS = ['index', 'spec', 'seed', 'outcome', 'why']


def row(index, outcome='stopped', why='stopped at the wall'):
    return {'index': index, 'spec': json.dumps({'world': 'wall', 'seed': index}), 'seed': index,
            'outcome': outcome, 'why': why}


def write_rows(path, count):
    rows, existing = rows_file.open_rows(str(path), COLUMNS)
    assert existing == []
    for i in range(count):
        rows.append(rows_file.csv_line(COLUMNS, row(i)))
    rows.close()


def test_rows_written_come_back_whole_and_a_line_break_in_a_cell_stays_in_its_row(tmp_path):
    path = tmp_path / 'rows.csv'
    rows, _ = rows_file.open_rows(str(path), COLUMNS)
    rows.append(rows_file.csv_line(COLUMNS, row(0, why='two\nlines, "quoted"')))
    rows.close()
    assert path.read_bytes().count(b'\n') == 2
    again, existing = rows_file.open_rows(str(path), COLUMNS)
    again.close()
    assert again.torn == 0 and [r['why'] for r in existing] == ['two lines, "quoted"']
    assert json.loads(existing[0]['spec']) == {'world': 'wall', 'seed': 0}


@pytest.mark.parametrize('cut', [1, 10, 40, -3, -1])
def test_a_torn_last_row_is_set_aside_with_its_bytes_and_its_episode_is_missing(tmp_path, cut):
    path = tmp_path / 'rows.csv'
    write_rows(path, 3)
    data = path.read_bytes()
    last = data.rstrip(b'\n').rfind(b'\n') + 1
    torn = data[:last + cut] if cut > 0 else data[:cut]
    path.write_bytes(torn)
    rows, existing = rows_file.open_rows(str(path), COLUMNS)
    rows.close()
    assert rows.torn == 1 and [r['index'] for r in existing] == ['0', '1']
    assert (tmp_path / 'rows.csv.torn').read_bytes() == torn[last:] + (b'' if torn.endswith(b'\n') else b'\n')
    assert path.read_bytes() == data[:last]


def test_a_torn_row_with_the_next_one_appended_onto_it_is_set_aside_not_counted(tmp_path):
    """What an older sweep did: a resumed run appended a whole row onto a torn one, making one corrupt line."""
    path = tmp_path / 'rows.csv'
    write_rows(path, 2)
    data = path.read_bytes()
    merged = data[:-20] + rows_file.csv_line(COLUMNS, row(2)).encode()
    path.write_bytes(merged)
    rows, existing = rows_file.open_rows(str(path), COLUMNS)
    rows.close()
    assert rows.torn == 1 and [r['index'] for r in existing] == ['0']
    assert (tmp_path / 'rows.csv.torn').read_bytes() == merged[merged.index(b'\n', merged.index(b'\n') + 1) + 1:]


def test_a_row_with_an_outcome_that_is_none_or_an_index_that_is_no_number_is_set_aside(tmp_path):
    path = tmp_path / 'rows.csv'
    write_rows(path, 1)
    with open(path, 'ab') as f:
        f.write(rows_file.csv_line(COLUMNS, row(1, outcome='""robot"": ""closed_loop""')).encode())
        f.write(rows_file.csv_line(COLUMNS, dict(row(2), index='two')).encode())
        f.write(b'\xff\xfe not text\r\n')
    rows, existing = rows_file.open_rows(str(path), COLUMNS)
    rows.close()
    assert rows.torn == 3 and [r['index'] for r in existing] == ['0']


def test_another_sweeps_file_is_refused_without_quoting_it(tmp_path):
    path = tmp_path / 'rows.csv'
    path.write_text('index,spec,secret_key,outcome,why\r\n')
    with pytest.raises(SweepError) as error:
        rows_file.open_rows(str(path), COLUMNS)
    assert 'another sweep' in str(error.value) and 'secret_key' not in str(error.value)


def test_a_torn_header_is_set_aside_and_written_again(tmp_path):
    path = tmp_path / 'rows.csv'
    path.write_bytes(b'index,sp')
    rows, existing = rows_file.open_rows(str(path), COLUMNS)
    rows.close()
    assert existing == [] and path.read_bytes() == (','.join(COLUMNS) + '\r\n').encode()
    assert (tmp_path / 'rows.csv.torn').read_bytes() == b'index,sp\n'


def test_rows_handed_one_at_a_time_are_the_rows_and_torn_ones_still_go_aside(tmp_path):
    """A resumed sweep takes its rows one at a time (``each``): the same rows as the list, none held by the file."""
    path = tmp_path / 'rows.csv'
    write_rows(path, 5)
    whole = path.read_bytes()
    path.write_bytes(whole + b'4,{"world": "wall"},4,stop')            # a last row torn by a kill
    seen = []
    rows, listed = rows_file.open_rows(str(path), COLUMNS, seen.append)
    rows.close()
    assert listed is None and rows.torn == 1 and rows.count == 6
    assert [r['index'] for r in seen] == ['0', '1', '2', '3', '4'] and seen[2] == {k: str(v) for k, v in row(2).items()}
    assert path.read_bytes() == whole and (tmp_path / 'rows.csv.torn').read_bytes() == b'4,{"world": "wall"},4,stop\n'
    assert not hasattr(rows, 'lines')


def test_a_line_ended_by_a_carriage_return_alone_is_a_line_of_its_own(tmp_path):
    """Lines are read as bytes.splitlines has them, a line at a time: a row cut between its CR and LF is torn, and
    the whole row after it is kept."""
    path = tmp_path / 'rows.csv'
    write_rows(path, 2)
    data = path.read_bytes()
    first_end = data.index(b'\r\n', data.index(b'\r\n') + 2)      # the end of row 0
    path.write_bytes(data[:first_end] + b'\r' + data[first_end + 2:])
    rows, existing = rows_file.open_rows(str(path), COLUMNS)
    rows.close()
    assert rows.torn == 1 and [r['index'] for r in existing] == ['1']
