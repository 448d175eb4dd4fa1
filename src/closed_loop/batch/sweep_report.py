"""What a sweep reports when it is done: the summary table (printed, and ``summary.txt``), the plot
(``plot.png``) and the page (``report.html``, ``closed_loop.batch.report_page``) beside ``rows.csv``, with
the pictures of its failing episodes (``pictures/episode-INDEX.png``, ``closed_loop.batch.pictures``).
Free of ROS."""
import os
import sys

from closed_loop.batch import report_page
from closed_loop.batch.tally import Tally, sortable

PICTURES = 'pictures'


def picture_path(output, index):
    """Where episode ``index``'s picture lives in a sweep's folder ``output``."""
    return os.path.join(output, PICTURES, 'episode-%05d.png' % int(index))


def table(tally):
    """(header, body) of the summary of ``tally`` (a ``closed_loop.batch.tally.Tally``): per combination of the
    grid's keys but ``seed``, the episodes, their outcomes, contact rate, least clearance and mean time, as
    strings."""
    header = tally.group_keys + ['episodes', 'outcomes', 'contact rate', 'min clearance', 'mean time']
    body = []
    for values, group in sorted(tally.groups.items(), key=lambda item: [sortable(v) for v in item[0]]):
        rate, mean_time = group.contact_rate(), group.mean_time()
        body.append([str(v) for v in values] + [
            str(group.episodes), ' '.join('%s %d' % kv for kv in sorted(group.outcomes.items())),
            '-' if rate is None else '%.2f' % rate, '%.3f m' % group.least if group.ran else '-',
            '-' if mean_time is None else '%.1f s' % mean_time])
    return header, body


def summarize(tally):
    """The summary :func:`table` as lines of text, in columns."""
    header, body = table(tally)
    lines = [header] + body
    widths = [max(len(str(line[i])) for line in lines) for i in range(len(header))]
    return ['  '.join(str(cell).ljust(w) for cell, w in zip(line, widths)).rstrip() for line in lines]


def plot(tally, x_key, line_key, path, title):
    """Contact rate and least clearance against ``x_key``, one line per value of ``line_key``, as a PNG."""
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot
    lines = tally.plot_points(x_key, line_key)
    figure, (top, bottom) = pyplot.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    for label, points in sorted(lines.items(), key=lambda item: sortable(item[0])):
        xs = sorted(points)
        name = '%s = %s' % (line_key.split('.')[-1], label) if line_key else None
        top.plot(xs, [points[x].contact_rate() for x in xs], 'o-', label=name)
        bottom.plot(xs, [points[x].least for x in xs], 'o-', label=name)
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


def default_plot(tally):
    """The plot a sweep without ``plot:`` gets: its first numeric grid key on x, the second as lines."""
    numeric = tally.numeric_keys()
    if not numeric:
        return None
    return {'x': numeric[0], 'lines': numeric[1] if len(numeric) > 1 else None}


def pictured(output):
    """The indices of the episodes whose picture is in the sweep's folder ``output``."""
    try:
        names = os.listdir(os.path.join(output, PICTURES))
    except FileNotFoundError:
        return set()
    numbers = [n[len('episode-'):-len('.png')] for n in names if n.startswith('episode-') and n.endswith('.png')]
    return {int(n) for n in numbers if n.isdigit()}


def report(sweep, rows, output, stream=sys.stdout, preface=()):
    """The summary table (printed, and ``summary.txt``), the plot if the sweep has an x to plot, and
    ``report.html`` (with ``preface``, lines to put first: a recommendation and its rule), from ``rows`` (an
    iterable of rows.csv's dicts, read once: ``closed_loop.batch.rows_file.Rows`` reads the file as it goes).
    Returns the rows' ``closed_loop.batch.tally.Tally``."""
    tally = Tally.of(rows, sweep.keys, plot=sweep.plot, listed=report_page.MAX_LISTED, pictured=pictured(output),
                     draw_all=sweep.report['pictures'] == 'all')
    text = '\n'.join(summarize(tally)) + '\n'
    stream.write(text)
    with open(os.path.join(output, 'summary.txt'), 'w') as f:
        f.write(text)
    choice = sweep.plot or default_plot(tally)
    plot_file = None
    if choice is not None:
        plot_file = os.path.join(output, 'plot.png')
        plot(tally, choice['x'], choice.get('lines'), plot_file, sweep.name)
        stream.write('plot: %s\n' % plot_file)
    page = os.path.join(output, 'report.html')
    header, body = table(tally)
    report_page.write(page, sweep, tally, header, body, plot_file, lambda i: picture_path(output, i), preface)
    stream.write('report: %s\n' % page)
    return tally
