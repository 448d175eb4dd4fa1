"""The docs say what the code says: every node's parameter table equals its settings classes (the one
declaration of each parameter), every link between the pages leads somewhere, and the README stays a short
start."""
import os
import re
import sys

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'tools'))
import param_tables  # noqa: E402

README_MAX_LINES = 260
LINK = re.compile(r'\]\(([^)\s]+)\)')


def pages():
    return [os.path.join(ROOT, 'README.md')] + param_tables.docs()


def anchors(path):
    """The heading anchors of a Markdown page, as GitHub makes them."""
    found = set()
    in_code = False
    for line in open(path):
        if line.startswith('```'):
            in_code = not in_code
        if not in_code and line.startswith('#'):
            title = line.lstrip('#').strip().lower()
            found.add(re.sub(r'[^\w\- ]', '', title).replace(' ', '-'))
    return found


def test_every_parameter_table_equals_its_settings_classes():
    assert param_tables.main(['--check']) == 0, 'run python3 tools/param_tables.py --write'


def test_every_node_with_parameters_has_a_table():
    marked = set()
    for path in param_tables.docs():
        marked |= set(re.findall(r'^<!-- parameters: (\w+) -->$', open(path).read(), re.M))
    assert marked == set(param_tables.node_settings()), 'missing %s, extra %s' % (
        sorted(set(param_tables.node_settings()) - marked), sorted(marked - set(param_tables.node_settings())))


def test_a_table_that_disagrees_is_caught():
    text = '<!-- parameters: stop_on_obstacle -->\n' + '\n'.join(param_tables.table('stop_on_obstacle'))
    assert param_tables.rewrite(text) == text
    assert param_tables.rewrite(text.replace('| 0.5 |', '| 0.6 |', 1)) == text


@pytest.mark.parametrize('page', [os.path.relpath(p, ROOT) for p in pages()])
def test_every_link_leads_somewhere(page):
    path = os.path.join(ROOT, page)
    text = open(path).read()
    for target in LINK.findall(text):
        if target.startswith(('http://', 'https://', 'mailto:')):
            continue
        file_part, _, anchor = target.partition('#')
        linked = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
        assert os.path.exists(linked), '%s links to %s, which does not exist' % (page, target)
        if anchor and linked.endswith('.md'):
            assert anchor in anchors(linked), '%s links to %s: no such heading' % (page, target)


def test_the_readme_is_a_short_start_that_leads_to_the_docs():
    lines = open(os.path.join(ROOT, 'README.md')).read().splitlines()
    assert len(lines) <= README_MAX_LINES, len(lines)
    text = '\n'.join(lines)
    assert text.index('make demo') < text.index('## A five-minute tour')
    for page in param_tables.docs():
        assert 'docs/' + os.path.basename(page) in text, 'README does not lead to %s' % page


def test_a_file_the_docs_show_whole_is_the_file_the_tests_run():
    """``<!-- own-test: PATH -->`` before a code block: the block is PATH as it stands (a copied test file that
    the tests run, so the page cannot drift from it)."""
    marker = re.compile(r'^<!-- own-test: (\S+) -->$')
    shown = 0
    for page in pages():
        lines = open(page).read().split('\n')
        for i, line in enumerate(lines):
            match = marker.match(line)
            if match:
                assert lines[i + 1].startswith('```'), '%s:%d: no code block after the marker' % (page, i + 1)
                end = next(j for j in range(i + 2, len(lines)) if lines[j].startswith('```'))
                with open(os.path.join(ROOT, match.group(1))) as f:
                    assert '\n'.join(lines[i + 2:end]) + '\n' == f.read(), '%s:%d: differs from %s' % (
                        page, i + 1, match.group(1))
                shown += 1
    assert shown >= 1
