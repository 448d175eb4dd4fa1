"""A sweep's page, ``report.html``: one self-contained file beside ``rows.csv`` that works from the folder,
offline (no script, style or font from anywhere else; the pictures are files beside it), on a phone as on a
wide screen. It shows, top to bottom: what was found (a recommendation and its rule, where the command made
one), the headline (episodes, outcomes, success, contacts, time, and the BARN benchmark's score in worlds of its
method), what did not go as meant (a table of it, then each drawn episode's picture with its result and spec),
the summary table (sortable: click a column's heading; folded when it is long), the plot, and the sweep file.
Free of ROS.
"""
import html
import json
import os

from closed_loop.sim import barn_score

#: The failing episodes the page lists, at most (the rest are in rows.csv).
MAX_LISTED = 1000
#: A summary table longer than this (rows) is folded: the page opens on the headline and the failures.
FOLD_ROWS = 20
RESULT_FIELDS = ('outcome', 'time_s', 'min_clearance_m', 'contacts', 'final_x', 'final_y', 'final_yaw',
                 'goal_error_m', 'path_m', 'error', 'logs')

STYLE = """
:root { color-scheme: light; --ink: #1d1d1f; --muted: #5f6368; --line: #d9d9de; --bad: #b3261e; --good: #1e7a34; }
* { box-sizing: border-box; }
body { margin: 0 auto; max-width: 72rem; padding: 1rem; color: var(--ink); background: #fff;
       font: 15px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif; }
h1 { font-size: 1.5rem; margin: 0.2rem 0 0.6rem; } h2 { font-size: 1.15rem; margin: 1.6rem 0 0.5rem; }
.preface { border-left: 4px solid var(--good); background: #f3f8f4; padding: 0.5rem 0.8rem; }
.preface p { margin: 0.25rem 0; }
.outcomes span { display: inline-block; margin: 0 0.8rem 0.3rem 0; }
.bad { color: var(--bad); font-weight: 600; }
.scroll { overflow-x: auto; -webkit-overflow-scrolling: touch; border: 1px solid var(--line); border-radius: 6px; }
table { border-collapse: collapse; width: 100%; font-size: 0.9rem; }
th, td { padding: 0.3rem 0.55rem; border-bottom: 1px solid var(--line); text-align: left; vertical-align: top; }
td { overflow-wrap: anywhere; min-width: 3.5rem; }
td.why { min-width: 16rem; }
th { background: #f5f5f7; position: sticky; top: 0; white-space: nowrap; }
th button { all: unset; cursor: pointer; font-weight: 600; }
th button:focus-visible { outline: 2px solid #1a73e8; }
th[aria-sort=ascending] button::after { content: " \\25B2"; } th[aria-sort=descending] button::after { content: " \\25BC"; }
img { max-width: 100%; height: auto; display: block; }
figure { margin: 1rem 0 1.6rem; border: 1px solid var(--line); border-radius: 6px; padding: 0.5rem; }
figcaption { font-size: 0.9rem; margin-top: 0.4rem; }
pre { white-space: pre-wrap; overflow-wrap: anywhere; background: #f7f7f9; padding: 0.6rem; border-radius: 6px;
      font: 0.82rem/1.4 ui-monospace, "DejaVu Sans Mono", monospace; }
code { font-family: ui-monospace, "DejaVu Sans Mono", monospace; font-size: 0.9em; }
.muted { color: var(--muted); }
@media (max-width: 40rem) { body { padding: 0.6rem; font-size: 14px; } th, td { padding: 0.25rem 0.4rem; } }
"""

SCRIPT = """
(function () {
  function key(cell) { return cell.getAttribute('data-sort') || cell.textContent.trim(); }
  function compare(a, b) {
    var x = parseFloat(a), y = parseFloat(b);
    if (!isNaN(x) && !isNaN(y)) { return x - y; }
    if (!isNaN(x)) { return -1; }
    if (!isNaN(y)) { return 1; }
    return a.localeCompare(b);
  }
  Array.prototype.forEach.call(document.querySelectorAll('table.sortable'), function (table) {
    var heads = table.querySelectorAll('th');
    Array.prototype.forEach.call(heads, function (th, column) {
      th.querySelector('button').addEventListener('click', function () {
        var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
        var direction = th.getAttribute('aria-sort') === 'ascending' ? -1 : 1;
        Array.prototype.forEach.call(heads, function (h) { h.removeAttribute('aria-sort'); });
        th.setAttribute('aria-sort', direction === 1 ? 'ascending' : 'descending');
        rows.sort(function (a, b) { return direction * compare(key(a.cells[column]), key(b.cells[column])); });
        rows.forEach(function (row) { body.appendChild(row); });
      });
    });
  });
}());
"""


class _Why(str):
    """A table cell of prose (a verdict's line), given room to wrap."""


def esc(value):
    """``value`` as HTML text."""
    return html.escape(str(value), quote=True)


def table(header, body, css_id):
    """A sortable table: ``header`` (names), ``body`` (rows of HTML cells; a :class:`_Why` cell is escaped prose)."""
    head = ''.join('<th scope="col"><button type="button">%s</button></th>' % esc(h) for h in header)
    rows = ''.join('<tr>%s</tr>' % ''.join('<td class="why">%s</td>' % esc(cell) if isinstance(cell, _Why)
                                           else '<td>%s</td>' % cell for cell in row) for row in body)
    return ('<div class="scroll"><table class="sortable" id="%s"><thead><tr>%s</tr></thead><tbody>%s</tbody>'
            '</table></div>' % (css_id, head, rows))


def _outcomes(tally):
    counts = tally.outcomes()
    spans = ''.join('<span%s>%s: %d</span>' % (' class="bad"' if outcome in ('collided', 'failed', 'timed_out', 'error')
                                               else '', esc(outcome), n) for outcome, n in sorted(counts.items()))
    headline = '<span>as meant: %.1f%%</span><span%s>contacts: %d</span>' % (
        100.0 * (tally.rows - tally.failing) / tally.rows if tally.rows else 0.0, ' class="bad"' if tally.contacts
        else '', tally.contacts)
    if tally.times:
        headline += '<span>time: mean %.1f s, longest %.1f s</span>' % (tally.time_sum / tally.times, tally.longest)
    if tally.scores:
        headline += ('<span>the BARN benchmark\'s score: mean %.3f over %d episodes (at most %.1f)</span>'
                     % (tally.score_sum / tally.scores, tally.scores, barn_score.BEST))
    return '<p class="outcomes"><span>%d episodes</span>%s<span class="bad">not as meant: %d</span>%s</p>' % (
        tally.rows, spans, tally.failing, headline)


def _result(row):
    cells = ''.join('<tr><th scope="row">%s</th><td>%s</td></tr>' % (esc(k), esc(row.get(k, '')))
                    for k in RESULT_FIELDS if row.get(k, '') != '')
    return '<div class="scroll"><table>%s</table></div>' % cells


def _spec(row):
    try:
        return json.dumps(json.loads(row['spec']), indent=2, sort_keys=True)
    except (KeyError, ValueError):
        return row.get('spec', '')


def write(path, sweep, tally, header, body, plot_file, picture_of, preface=()):
    """Write the page to ``path``: ``sweep`` (a ``closed_loop.batch.sweep_file.Sweep``), its rows' ``tally`` (a
    ``closed_loop.batch.tally.Tally`` kept with at least :data:`MAX_LISTED` failing rows and the indices that
    have pictures), the summary table (``header``, ``body``), the plot's file (or None), ``picture_of(index)``:
    an episode's picture file, ``preface``: lines to put first."""
    folder = os.path.dirname(os.path.abspath(path))
    parts = ['<!DOCTYPE html>', '<html lang="en"><head><meta charset="utf-8">',
             '<meta name="viewport" content="width=device-width, initial-scale=1">',
             '<title>sweep %s</title><style>%s</style></head><body>' % (esc(sweep.name), STYLE),
             '<h1>sweep <code>%s</code></h1>' % esc(sweep.name)]
    if preface:
        parts.append('<section class="preface" id="preface">%s</section>' % ''.join('<p>%s</p>' % esc(line) for line in preface))
    parts.append(_outcomes(tally))
    drawn = tally.drawn_rows()
    drawn_ids = {r['index'] for r in drawn}
    if tally.failing:
        listed = tally.listed_rows()[:MAX_LISTED]
        keys = list(sweep.keys)
        body_rows = [['<a href="#episode-%s">%s</a>' % (esc(r['index']), esc(r['index']))
                      if r['index'] in drawn_ids else esc(r['index']), esc(r['outcome']), esc(r.get('contacts', ''))]
                     + [esc(r.get(k, '')) for k in keys] + [_Why(r.get('why') or r.get('error', ''))] for r in listed]
        parts.append('<h2>Not as meant (%d)</h2>' % tally.failing)
        parts.append(table(['index', 'outcome', 'contacts'] + keys + ['why'], body_rows, 'failing'))
        if tally.failing > len(listed):
            parts.append('<p class="muted">The first %d are listed; rows.csv has them all.</p>' % len(listed))
    parts.append('<h2>Pictures (%d)</h2>' % len(drawn))
    parts.append('<p class="muted">Any episode again, as a picture or a bag to replay in rviz: <code>rosrun closed_loop '
                 'episode_plot %s INDEX</code>, <code>rosrun closed_loop episode_bag %s INDEX</code>.</p>'
                 % (esc(folder), esc(folder)))
    for r in drawn:
        parts.append('<figure id="episode-%s"><a href="%s"><img src="%s" alt="episode %s: %s" decoding="async"></a><figcaption>'
                     '<strong>episode %s</strong>: %s%s<details><summary>spec</summary><pre>%s</pre></details>'
                     '</figcaption></figure>' % (
                         esc(r['index']), esc(os.path.relpath(picture_of(r['index']), folder)),
                         esc(os.path.relpath(picture_of(r['index']), folder)), esc(r['index']),
                         esc(r['outcome']), esc(r['index']), esc(r.get('why') or r.get('error', '')), _result(r),
                         esc(_spec(r))))
    summary = table(header, [[esc(c) for c in line] for line in body], 'summary')
    if len(body) > FOLD_ROWS:
        summary = '<details><summary>%d rows (open)</summary>%s</details>' % (len(body), summary)
    parts.append('<h2>Summary</h2>' + summary)
    if plot_file and os.path.exists(plot_file):
        parts.append('<h2>Plot</h2><img src="%s" alt="contact rate and least clearance against the grid" '
                     'width="700" height="650">' % esc(os.path.relpath(plot_file, folder)))
    parts.append('<h2>The sweep</h2><pre>%s</pre>' % esc(getattr(sweep, 'text', '') or ''))
    parts.append('<script>%s</script></body></html>' % SCRIPT)
    tmp = path + '.tmp'
    with open(tmp, 'w', encoding='utf-8') as f:
        f.write('\n'.join(parts) + '\n')
    os.replace(tmp, path)
