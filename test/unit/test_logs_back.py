"""A graph episode's folder packed on a worker and unpacked on the client (closed_loop.batch.logs_back): every file
back as it was within the limit, the verdict and the launch file first whatever their size, what is past the limit
named and left, nothing written outside the folder, and the mark that tells a worker whether it sees the
client's files."""
import io
import os
import tarfile

from closed_loop.batch import logs_back


def episode_folder(root):
    folder = root / 'episode'
    (folder / 'log' / 'run').mkdir(parents=True)
    (folder / 'verdict.json').write_text('{"outcome": "stopped"}' + ' ' * 5000)
    (folder / 'episode.launch').write_text('<launch/>')
    (folder / 'graph.log').write_text('graph\n' * 100)
    (folder / 'log' / 'run' / 'sim-1.log').write_text('sim\n' * 1000)
    (folder / 'log' / 'run' / 'big.log').write_bytes(os.urandom(20000))
    return folder


def files_of(folder):
    return {os.path.relpath(os.path.join(top, n), str(folder)): open(os.path.join(top, n), 'rb').read()
            for top, _, names in os.walk(str(folder)) for n in names}


def test_a_folder_comes_back_whole_within_the_limit(tmp_path):
    folder = episode_folder(tmp_path)
    data, left = logs_back.pack(str(folder))
    assert left == []
    logs_back.unpack(data, str(tmp_path / 'client'))
    assert files_of(tmp_path / 'client') == files_of(folder)


def test_past_the_limit_the_largest_stay_and_are_named_the_verdict_always_comes(tmp_path):
    folder = episode_folder(tmp_path)
    data, left = logs_back.pack(str(folder), limit=6000)
    assert left == [os.path.join('log', 'run', 'sim-1.log'), os.path.join('log', 'run', 'big.log')], left
    logs_back.unpack(data, str(tmp_path / 'client'))
    back = files_of(tmp_path / 'client')
    assert set(back) == {'verdict.json', 'episode.launch', 'graph.log'}       # the verdict alone is past 5000
    row = {}
    logs_back.send_back(str(folder), row, limit=6000)
    assert folder.exists() and 'sim-1.log' in row['logs_left'] and str(folder) in row['logs_left']
    logs_back.receive(row, str(tmp_path / 'again'), lambda f: None)
    assert 'stayed on the worker' in (tmp_path / 'again' / logs_back.LEFT_NOTE).read_text()
    assert 'logs_packed' not in row and 'logs_left' not in row
    row = {}
    logs_back.send_back(str(folder), row)                                       # all of it: the folder goes
    assert not folder.exists() and 'logs_left' not in row


def test_nothing_is_written_outside_the_folder(tmp_path):
    data = io.BytesIO()
    with tarfile.open(fileobj=data, mode='w:gz') as tar:
        for name in ('../escaped', '/abs/escaped', 'inside/ok'):
            info = tarfile.TarInfo(name)
            info.size = 2
            tar.addfile(info, io.BytesIO(b'hi'))
        link = tarfile.TarInfo('link')
        link.type, link.linkname = tarfile.SYMTYPE, '/etc/passwd'
        tar.addfile(link)
    logs_back.unpack(data.getvalue(), str(tmp_path / 'client'))
    assert files_of(tmp_path / 'client') == {os.path.join('inside', 'ok'): b'hi'}
    assert not (tmp_path / 'escaped').exists() and not os.path.exists('/abs/escaped')


def test_a_worker_sees_the_clients_files_by_its_mark(tmp_path):
    token = logs_back.claim(str(tmp_path / 'graphs'))
    assert logs_back.shares(str(tmp_path / 'graphs'), token)
    assert not logs_back.shares(str(tmp_path / 'graphs'), 'another client')
    assert not logs_back.shares(str(tmp_path / 'elsewhere'), token)
