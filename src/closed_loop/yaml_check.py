"""Reading a YAML input file strictly, and checking its fields, with errors a person can act on.

Every error is a :class:`FileError` (or a subclass a module gives, such as
:class:`closed_loop.sim.world.WorldError`) whose message names the file, the field and what was
expected, on one line, quoting at most a short excerpt of the offending value:
``"worlds/wall.yaml: obstacles[0].size: expected 3 numbers > 0 (m), got [0.1, 4.0]"``.
Free of ROS; world files use it, and any later input file (a sweep spec) can.
"""
import math
import os
import re
import reprlib

import yaml

#: At most this many characters of an offending value are quoted in an error message.
MAX_QUOTE_CHARS = 120
# Marks a required key that is absent, so messages can say so instead of printing a value.
MISSING = object()
_MERGE_TAG = 'tag:yaml.org,2002:merge'
#: A key an error may quote: a name, as every key of our files is.
KEY_NAME = re.compile(r'^[A-Za-z_][A-Za-z0-9_.-]{0,63}$')


_SHORT = reprlib.Repr()
_SHORT.maxlevel, _SHORT.maxlist, _SHORT.maxtuple, _SHORT.maxdict = 3, 8, 8, 8
_SHORT.maxstring = _SHORT.maxother = _SHORT.maxlong = MAX_QUOTE_CHARS


def quote(value, limit=MAX_QUOTE_CHARS):
    """``repr(value)`` on one line, cut to ``limit`` characters (a deep or huge value, such as a YAML alias
    bomb, is never written out whole: nested and long parts are elided before they are made)."""
    if isinstance(value, Kind):
        return value.text
    text = ' '.join(_SHORT.repr(value).splitlines())
    if isinstance(value, str) and len(value) + 2 > limit:
        return '%s... (%d characters in all)' % (text[:limit], len(value) + 2)
    return text if len(text) <= limit else text[:limit] + '...'


class Kind:
    """What a value is, without its content: for a file that did not parse as the YAML expected (a file
    that is no world, no sweep), whose content an error must not show."""

    def __init__(self, value):
        if isinstance(value, str):
            self.text = 'text (%d characters), not a mapping' % len(value)
        elif isinstance(value, (list, tuple)):
            self.text = 'a list of %d items' % len(value)
        elif value is None:
            self.text = 'an empty document'
        else:
            self.text = 'a %s' % type(value).__name__

    @classmethod
    def said(cls, text):
        """A parser's own words about a problem (no content of the file beyond what it names), cut short."""
        kind = cls(None)
        words = ' '.join(str(text).split())
        kind.text = words if len(words) <= MAX_QUOTE_CHARS else words[:MAX_QUOTE_CHARS] + '...'
        return kind


class FileError(ValueError):
    """An input file is unusable: ``"<file>: <field path>: expected <what>, got <value>"``.

    The parts are kept as attributes ``source``, ``field``, ``expected`` and ``got`` (the offending
    value, or None when the field is missing).
    """

    def __init__(self, source, field, expected, got=MISSING):
        self.source = source
        self.field = field
        self.expected = expected
        self.got = None if got is MISSING else got
        told = 'nothing (the key is missing)' if got is MISSING else quote(got)
        super().__init__('%s: %s: expected %s, got %s' % (source, field, expected, told))


def read_text(path, max_bytes, error_class=FileError, what='file'):
    """The UTF-8 text of ``path``, refused (``error_class``) if unreadable, not UTF-8 or over ``max_bytes``.

    The size is checked before reading, and the read stops one byte past the limit, so a huge file (or a
    pipe) costs nothing.
    """
    try:
        with open(path, 'r', encoding='utf-8') as stream:
            size = os.fstat(stream.fileno()).st_size
            if size > max_bytes:
                raise error_class(path, '(file)', 'a %s of at most %d bytes' % (what, max_bytes), '%d bytes' % size)
            text = stream.read(max_bytes + 1)
            if len(text.encode('utf-8')) > max_bytes:
                raise error_class(path, '(file)', 'a %s of at most %d bytes' % (what, max_bytes), 'more')
    except OSError as error:
        raise error_class(path, '(file)', 'a readable %s' % what, error.strerror or str(error)) from None
    except UnicodeDecodeError as error:
        raise error_class(path, '(file)', 'UTF-8 text', str(error)) from None
    return text


class StrictLoader(getattr(yaml, 'CSafeLoader', yaml.SafeLoader)):
    """PyYAML's safe loader, except that a key repeated in one mapping is an error.

    PyYAML keeps the last of two equal keys without a word, which hides typos such as an obstacle
    given two ``position`` lines. It parses with libyaml where PyYAML has it (Debian's and Ubuntu's
    python3-yaml do): a world of 200 obstacles is read in a tenth of the time.
    """

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen = set()
            for key_node, _ in node.value:
                # Merge keys (<<) may legitimately repeat keys; only literal keys are checked.
                if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == _MERGE_TAG:
                    continue
                key = self.construct_object(key_node, deep=True)
                if key in seen:
                    raise yaml.constructor.ConstructorError(
                        'while constructing a mapping', node.start_mark,
                        'found duplicate key %r' % (key,), key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


def load_yaml(text, source, error_class=FileError):
    """Parse YAML ``text``; a syntax error becomes ``error_class`` naming ``source`` and the line."""
    try:
        return yaml.load(text, Loader=StrictLoader)
    except yaml.MarkedYAMLError as error:
        mark = error.problem_mark or error.context_mark
        where = 'line %d, column %d' % (mark.line + 1, mark.column + 1) if mark else 'somewhere'
        problem = error.problem or error.context or 'a syntax error'
        if error.context and error.context_mark and error.context_mark is not mark:
            # The start of the unclosed bracket or block is often the real culprit.
            problem = '%s (%s started on line %d)' % (problem, error.context,
                                                      error.context_mark.line + 1)
        raise error_class(source, where, 'valid YAML', Kind.said(problem)) from None
    except yaml.YAMLError as error:
        raise error_class(source, '(file)', 'valid YAML', Kind.said(type(error).__name__)) from None


def finite_float(value):
    """``value`` as a float if it is a finite int or float, else None.

    Booleans are refused although Python counts them as ints (``size: [true, 1, 1]`` is a typo,
    not 1.0), and so are strings: YAML 1.1 reads ``1e3`` (no dot) as a string.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


class Checker:
    """Field checks that all report errors (``error_class``) against one source file."""

    def __init__(self, source, error_class=FileError):
        self.source = source
        self.error_class = error_class

    def fail(self, field, expected, got=MISSING):
        raise self.error_class(self.source, field, expected, got)

    def get(self, data, key, field, default=MISSING):
        """``data[key]``, or ``default``; a missing required key (no default) is an error."""
        if key in data:
            return data[key]
        if default is MISSING:
            self.fail(field, 'a value for the required key %r' % key)
        return default

    def mapping(self, value, field, allowed):
        """``value`` must be a mapping whose keys are all in ``allowed``."""
        if not isinstance(value, dict):
            # A document that is not a mapping at all is not this kind of file: its content is not shown.
            self.fail(field, 'a mapping', Kind(value) if field == '(top level)' else value)
        for key in value:
            if key not in allowed:
                if not isinstance(key, str) or not KEY_NAME.match(key):
                    # Not even a name: likely a file of another kind, whose content is not shown.
                    self.fail(field, 'only known keys (%s)' % ', '.join(allowed), Kind.said(
                        'a key that is no name (%d characters)' % len(str(key))))
                sub = '%s.%s' % (field, key) if field != '(top level)' else str(key)
                self.fail(sub, 'a known key (%s)' % ', '.join(allowed), key)
        return value

    def number(self, value, field, what='a finite number', positive=False):
        """A finite int or float (not a bool, not a string), as float; ``positive``: also > 0."""
        number = finite_float(value)
        if number is None or (positive and not number > 0.0):
            self.fail(field, what, value)
        return number

    def string(self, value, field):
        if not isinstance(value, str) or not value.strip():
            self.fail(field, 'a non-empty string', value)
        return value

    def numbers(self, value, field, counts, what, positive=False):
        """A list of ``counts`` (a tuple of allowed lengths) numbers, as a tuple of floats."""
        if not isinstance(value, (list, tuple)) or len(value) not in counts:
            self.fail(field, what, value)
        numbers = tuple(finite_float(item) for item in value)
        # Report the whole list: "got [1.0, nan]" is clearer than an index into it.
        if any(n is None or (positive and not n > 0.0) for n in numbers):
            self.fail(field, what, value)
        return numbers
