"""What a sweep reports when it is done: the summary table (printed, and ``summary.txt``), the plot
(``plot.png``) and the page (``report.html``, ``closed_loop.batch.report_page``) beside ``rows.csv``, with
the pictures of its failing episodes (``pictures/episode-INDEX.png``, ``closed_loop.batch.pictures``).
Free of ROS."""
import os
import sys

import numpy

from closed_loop.batch import report_page

PICTURES = 'pictures'


def picture_path(output, index):
    """Where episode ``index``'s picture lives in a sweep's folder ``output``."""
    return os.path.join(output, PICTURES, 'episode-%05d.png' % int(index))


def table(rows, keys):
    """(header, body) of the summary: per combination of the grid's keys but ``seed``, the episodes, their
    outcomes, contact rate, least clearance and mean time, as strings."""
    group_keys = [k for k in keys if k != 'seed']
    groups = {}
    for row in rows:
        groups.setdefault(tuple(row.get(k, '') for k in group_keys), []).append(row)
    header = group_keys + ['episodes', 'outcomes', 'contact rate', 'min clearance', 'mean time']
    body = []
    for values, members in sorted(groups.items(), key=lambda item: [sortable(v) for v in item[0]]):
        outcomes = {}
        for row in members:
            outcomes[row['outcome']] = outcomes.get(row['outcome'], 0) + 1
        ran = [r for r in members if r['outcome'] != 'error']
        clear = [float(r['min_clearance_m']) for r in ran]
        times = [float(r['time_s']) for r in ran]
        contacts = [int(r['contacts']) > 0 for r in ran]
        body.append([str(v) for v in values] + [
            str(len(members)), ' '.join('%s %d' % kv for kv in sorted(outcomes.items())),
            '%.2f' % numpy.mean(contacts) if contacts else '-', '%.3f m' % min(clear) if clear else '-',
            '%.1f s' % numpy.mean(times) if times else '-'])
    return header, body


def summarize(rows, keys):
    """The summary :func:`table` as lines of text, in columns."""
    header, body = table(rows, keys)
    lines = [header] + body
    widths = [max(len(str(line[i])) for line in lines) for i in range(len(header))]
    return ['  '.join(str(cell).ljust(w) for cell, w in zip(line, widths)).rstrip() for line in lines]


def sortable(value):
    """A key that sorts numbers by value, before text."""
    try:
        return (0, float(value), '')
    except (TypeError, ValueError):
        return (1, 0.0, str(value))


def plot(rows, x_key, line_key, path, title):
    """Contact rate and least clearance against ``x_key``, one line per value of ``line_key``, as a PNG."""
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot
    lines = {}
    for row in rows:
        if row['outcome'] == 'error':
            continue
        group = lines.setdefault(row.get(line_key, '') if line_key else '', {})
        group.setdefault(float(row[x_key]), []).append(row)
    figure, (top, bottom) = pyplot.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    for label, points in sorted(lines.items(), key=lambda item: sortable(item[0])):
        xs = sorted(points)
        name = '%s = %s' % (line_key.split('.')[-1], label) if line_key else None
        top.plot(xs, [numpy.mean([int(r['contacts']) > 0 for r in points[x]]) for x in xs], 'o-', label=name)
        bottom.plot(xs, [min(float(r['min_clearance_m']) for r in points[x]) for x in xs], 'o-', label=name)
    top.set_ylabel('contact rate')
    top.set_ylim(-0.05, 1.05)
    bottom.set_ylabel('least clearance (m, ground truth)')
    bottom.axhline(0.0, color='grey', linewidth=0.8)
    bottom.set_xlabel(x_key)
    for axes in (top, bottom):
        axes.grid(True, alpha=0.3)
        if line_key:
            axes.legend()
    top.set_title(title)
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    pyplot.close(figure)


def default_plot(keys, rows):
    """The plot a sweep without ``plot:`` gets: its first numeric grid key on x, the second as lines."""
    numeric = [k for k in keys if k != 'seed' and rows and all(sortable(r.get(k))[0] == 0 for r in rows)]
    if not numeric:
        return None
    return {'x': numeric[0], 'lines': numeric[1] if len(numeric) > 1 else None}


def report(sweep, rows, output, stream=sys.stdout, preface=()):
    """The summary table (printed, and ``summary.txt``), the plot if the sweep has an x to plot, and
    ``report.html`` (with ``preface``, lines to put first: a recommendation and its rule)."""
    lines = summarize(rows, sweep.keys)
    text = '\n'.join(lines) + '\n'
    stream.write(text)
    with open(os.path.join(output, 'summary.txt'), 'w') as f:
        f.write(text)
    choice = sweep.plot or default_plot(sweep.keys, rows)
    plot_file = None
    if choice is not None:
        plot_file = os.path.join(output, 'plot.png')
        plot(rows, choice['x'], choice.get('lines'), plot_file, sweep.name)
        stream.write('plot: %s\n' % plot_file)
    page = os.path.join(output, 'report.html')
    header, body = table(rows, sweep.keys)
    report_page.write(page, sweep, rows, header, body, plot_file, lambda i: picture_path(output, i), preface)
    stream.write('report: %s\n' % page)
