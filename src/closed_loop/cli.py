"""What every command-line program of the package shares: ``--help`` gives each option's default.

An option's default is written after its help as ``(default: VALUE)``, a list as it is typed (``0.3,0.5``), a
flag's as ``off``; an option whose default is worked out at run time (None) says what it is in its own help,
with the word ``default``. A required option has none.
"""
import argparse


class ShowDefaults(argparse.HelpFormatter):
    def _get_help_string(self, action):
        text = action.help or ''
        if not action.option_strings or action.required or action.default in (None, argparse.SUPPRESS) \
                or 'default' in text:
            return text
        if action.nargs == 0:
            shown = 'on' if action.default else 'off'
        elif isinstance(action.default, (list, tuple)):
            shown = ','.join(str(value) for value in action.default)
        else:
            shown = str(action.default)
        return '%s%s(default: %s)' % (text, ' ' if text else '', shown.replace('%', '%%'))


def parser(prog, description, **kwargs):
    """An ``argparse.ArgumentParser`` whose ``--help`` gives each option's default (:class:`ShowDefaults`)."""
    return argparse.ArgumentParser(prog=prog, description=description, formatter_class=ShowDefaults, **kwargs)


def interrupted(error):
    """Whether ``error`` is Ctrl-C, or an error a library raised while Ctrl-C unwound it: a KeyboardInterrupt
    inside a ``with condition:`` (Dask's ``as_completed`` waiting) can leave ``RuntimeError: cannot release
    un-acquired lock``, whose ``__context__`` is the KeyboardInterrupt."""
    seen = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__context__
    return False
