"""The strict YAML reader and field checker on their own: any input file gets one-line errors naming the
file, the field and what was expected."""
import pytest

from closed_loop.yaml_check import Checker, FileError, load_yaml, read_text


class SpecError(FileError):
    """What another input file's module would raise."""


def test_errors_name_file_field_and_expectation_in_the_given_class():
    check = Checker('sweep.yaml', SpecError)
    data = load_yaml('seeds: [1, 2]\nspeed: fast\n', 'sweep.yaml', SpecError)
    with pytest.raises(SpecError, match=r"^sweep.yaml: speed: expected a finite number > 0 \(m/s\), got 'fast'$"):
        check.number(check.get(data, 'speed', 'speed'), 'speed', 'a finite number > 0 (m/s)', positive=True)
    with pytest.raises(SpecError, match="required key 'worlds'"):
        check.get(data, 'worlds', 'worlds')
    assert check.numbers(data['seeds'], 'seeds', (2,), 'two numbers') == (1.0, 2.0)


def test_duplicate_keys_and_syntax_errors_are_refused_with_the_line():
    with pytest.raises(FileError, match="line 2.*duplicate key 'a'"):
        load_yaml('a: 1\na: 2\n', 'f.yaml')
    with pytest.raises(FileError, match='line'):
        load_yaml('a: [1, 2\n', 'f.yaml')


def test_read_text_limits_size_before_reading(tmp_path):
    path = tmp_path / 'f.yaml'
    path.write_text('x' * 11)
    assert read_text(str(path), 11) == 'x' * 11
    with pytest.raises(FileError, match='at most 10 bytes'):
        read_text(str(path), 10)
    with pytest.raises(FileError, match='a readable file'):
        read_text(str(tmp_path / 'missing.yaml'), 10)
