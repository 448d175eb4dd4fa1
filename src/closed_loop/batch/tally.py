"""What a sweep's report needs of its rows, gathered in one pass over them (``Tally.add``, row by row as
``rows.csv`` is read): per combination of the grid's keys but ``seed``, the episodes' outcomes, contacts, least
clearance and time (the summary table and the plot); the headline's counts; and whole rows only where the page
shows them: the failing episodes it lists (the ``listed`` of lowest index) and those it draws (one per picture
file). So a sweep's report takes memory that grows with its grid's combinations, the list and the pictures, not
with its episodes. Free of ROS.
"""
import heapq
import math

from closed_loop.batch.pictures import is_failure


class Group:
    """Episodes of one kind (a combination of keys, or a point of the plot): how many, their outcomes, and of
    those that ran, how many touched anything, the least clearance and the sum of their times."""
    __slots__ = ('episodes', 'outcomes', 'ran', 'touched', 'least', 'time_sum')

    def __init__(self):
        self.episodes, self.outcomes, self.ran, self.touched, self.least, self.time_sum = 0, {}, 0, 0, math.inf, 0.0

    def add(self, row):
        self.episodes += 1
        self.outcomes[row['outcome']] = self.outcomes.get(row['outcome'], 0) + 1
        if row['outcome'] == 'error':
            return
        self.ran += 1
        self.touched += int(row['contacts']) > 0
        self.least = min(self.least, float(row['min_clearance_m']))
        self.time_sum += float(row['time_s'])

    def merge(self, other):
        self.episodes += other.episodes
        for outcome, n in other.outcomes.items():
            self.outcomes[outcome] = self.outcomes.get(outcome, 0) + n
        self.ran += other.ran
        self.touched += other.touched
        self.least = min(self.least, other.least)
        self.time_sum += other.time_sum

    def contact_rate(self):
        return self.touched / self.ran if self.ran else None

    def mean_time(self):
        return self.time_sum / self.ran if self.ran else None


class Tally:
    """A sweep's rows, tallied: ``keys`` (the grid's), ``plot`` (the sweep's own ``{'x', 'lines'}`` choice, or
    None), ``listed`` (how many failing rows to keep), ``pictured`` (the indices that have a picture) and
    ``draw_all`` (a picture of every episode is drawn, not of the failing ones only)."""

    def __init__(self, keys, plot=None, listed=1000, pictured=(), draw_all=False):
        self.keys = list(keys)
        self.group_keys = [k for k in self.keys if k != 'seed']
        self.plot = plot
        self.listed, self.pictured, self.draw_all = listed, {int(i) for i in pictured}, draw_all
        self.groups, self.points = {}, {}
        self.rows = self.failing = self.contacts = self.times = self.scores = 0
        self.time_sum, self.longest, self.score_sum = 0.0, None, 0.0
        self._listed, self._drawn = [], []

    @classmethod
    def of(cls, rows, keys, **kwargs):
        """The tally of ``rows`` (an iterable of rows.csv's dicts)."""
        tally = cls(keys, **kwargs)
        for row in rows:
            tally.add(row)
        return tally

    def add(self, row):
        self.rows += 1
        self.groups.setdefault(tuple(row.get(k, '') for k in self.group_keys), Group()).add(row)
        if self.plot and row['outcome'] != 'error':
            line = row.get(self.plot['lines'], '') if self.plot.get('lines') else ''
            self.points.setdefault((line, float(row[self.plot['x']])), Group()).add(row)
        if str(row.get('contacts') or '0').isdigit():
            self.contacts += int(row.get('contacts') or 0)
        if number(row.get('time_s')):
            self.times += 1
            self.time_sum += float(row['time_s'])
            self.longest = max(self.longest or -math.inf, float(row['time_s']))
        if number(row.get('benchmark_score')):
            self.scores += 1
            self.score_sum += float(row['benchmark_score'])
        failing = is_failure(row['outcome'], row.get('contacts'))
        self.failing += failing
        index = int(row['index'])
        if failing:
            entry = (-index, self.rows, row)
            if len(self._listed) < self.listed:
                heapq.heappush(self._listed, entry)
            elif entry > self._listed[0]:
                heapq.heapreplace(self._listed, entry)
        if index in self.pictured and (failing or self.draw_all):
            self._drawn.append(row)

    def outcomes(self):
        """{outcome: episodes} over every row."""
        total = Group()
        for group in self.groups.values():
            total.merge(group)
        return total.outcomes

    def listed_rows(self):
        """The failing rows kept (those of lowest index), by index."""
        return [row for _, _, row in sorted(self._listed, reverse=True)]

    def drawn_rows(self):
        """The rows that have a picture to show, by index."""
        return sorted(self._drawn, key=lambda r: int(r['index']))

    def numeric_keys(self):
        """The grid's keys but ``seed`` whose every value is a number."""
        return [k for i, k in enumerate(self.group_keys)
                if self.groups and all(sortable(values[i])[0] == 0 for values in self.groups)]

    def plot_points(self, x_key, line_key):
        """{line value: {x: Group}}: the sweep's own plot choice as tallied, any other (of keys but ``seed``)
        from the groups."""
        lines = {}
        if self.plot and (x_key, line_key) == (self.plot['x'], self.plot.get('lines')):
            for (line, x), group in self.points.items():
                lines.setdefault(line, {})[x] = group
            return lines
        for values, group in self.groups.items():
            if group.ran == 0:
                continue
            named = dict(zip(self.group_keys, values))
            line = named[line_key] if line_key else ''
            point = lines.setdefault(line, {}).setdefault(float(named[x_key]), Group())
            point.merge(group)
        return lines


def number(text):
    """Whether ``text`` is a number (not NaN)."""
    try:
        return float(text) == float(text)
    except (TypeError, ValueError):
        return False


def sortable(value):
    """A key that sorts numbers by value, before text."""
    try:
        return (0, float(value), '')
    except (TypeError, ValueError):
        return (1, 0.0, str(value))
