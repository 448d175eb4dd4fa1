"""``compare.html``: a comparison of two sides of one scenario set (``closed_loop.batch.compare``), one
self-contained page beside the sides' folders: what the pairs say (counts, McNemar's test, the changes of
clearance and time with their intervals), the pairs that differ, regressions first, each regression's pictures
of A and B side by side, then every pair (folded when long). Free of ROS.
"""
import os

from closed_loop.batch.report_page import FOLD_ROWS, SCRIPT, STYLE, esc, table

SIDE_BY_SIDE = '.pair { display: grid; grid-template-columns: 1fr 1fr; gap: 0.5rem; } ' \
               '@media (max-width: 40rem) { .pair { grid-template-columns: 1fr; } }'
ORDER = ('regression', 'fix', 'neither', 'both')


def _cells(p, keys):
    return ([esc(p.index), esc(p.kind)] + [esc(p.a.get(k, '')) for k in keys]
            + [esc(p.a['outcome']), esc(p.b['outcome']), esc(p.a.get('min_clearance_m', '')),
               esc(p.b.get('min_clearance_m', '')), esc(p.a.get('time_s', '')), esc(p.b.get('time_s', ''))])


def write(path, name, keys, changes, comparison, drawn):
    """Write the page to ``path``: the set's ``name`` and grid ``keys``, each side's ``changes`` ({'a': {key:
    value}, 'b': ...}), the ``comparison``, and ``drawn`` {index: (A's picture or None, B's picture)} of the
    regressions drawn. Returns ``path``."""
    folder = os.path.dirname(os.path.abspath(path))
    header = ['index', 'pair'] + list(keys) + ['A', 'B', 'clearance A', 'clearance B', 'time A', 'time B']
    pairs = sorted(comparison.pairs, key=lambda p: (ORDER.index(p.kind), p.index))
    differ = [p for p in pairs if p.kind in ('regression', 'fix')]
    parts = ['<!DOCTYPE html>', '<html lang="en"><head><meta charset="utf-8">',
             '<meta name="viewport" content="width=device-width, initial-scale=1">',
             '<title>compare %s</title><style>%s %s</style></head><body>' % (esc(name), STYLE, SIDE_BY_SIDE),
             '<h1>compare <code>%s</code></h1>' % esc(name),
             '<p>A: <code>%s</code><br>B: <code>%s</code></p>' % tuple(
                 esc(', '.join('%s=%s' % kv for kv in changes[side].items()) or 'the sweep as it is')
                 for side in ('a', 'b')),
             '<section class="preface" id="verdict">%s</section>' % ''.join(
                 '<p%s>%s</p>' % (' class="bad"' if i == 0 and comparison.regressions else '', esc(line))
                 for i, line in enumerate(comparison.lines()))]
    parts.append('<h2>Pairs that differ (%d)</h2>' % len(differ))
    parts.append(table(header, [_cells(p, keys) for p in differ], 'differ') if differ else
                 '<p>None: A and B went the same way in every scenario.</p>')
    parts.append('<h2>Regressions, A beside B (%d drawn)</h2>' % len(drawn))
    for index, (a, b) in sorted(drawn.items()):
        figures = ''.join('<figure><img src="%s" alt="%s, episode %d" decoding="async"><figcaption>%s</figcaption>'
                          '</figure>' % (esc(os.path.relpath(picture, folder)), side, index, side)
                          if picture and os.path.exists(picture) else '<p class="muted">%s: no picture</p>' % side
                          for side, picture in (('A', a), ('B', b)))
        parts.append('<div class="pair" id="pair-%d">%s</div>' % (index, figures))
    every = table(header, [_cells(p, keys) for p in pairs], 'pairs')
    if len(pairs) > FOLD_ROWS:
        every = '<details><summary>%d pairs (open)</summary>%s</details>' % (len(pairs), every)
    parts.append('<h2>Every pair</h2>' + every)
    parts.append('<p class="muted">Each side\'s own page: <a href="a/report.html">A</a>, <a href="b/report.html">B'
                 '</a>.</p><script>%s</script></body></html>' % SCRIPT)
    with open(path, 'w') as f:
        f.write('\n'.join(parts))
    return path
