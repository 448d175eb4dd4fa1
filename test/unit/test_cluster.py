"""Where a sweep runs (closed_loop.batch.cluster): the scheduler named by --scheduler and --tls, refused in one
line where it is wrong; the warning for a plain tcp:// scheduler off loopback, once; and the certificates
(closed_loop.batch.certificates) a CA signs, for both ends of a connection, with the hosts named."""
import io
import os
import ssl
import subprocess

import pytest

from closed_loop.batch import certificates, cluster


@pytest.fixture(scope='module')
def certs(tmp_path_factory):
    folder = tmp_path_factory.mktemp('certs')
    certificates.make(str(folder), hosts=['lab-1', '10.0.0.5'], days=30)
    return folder


def test_a_scheduler_is_named_as_dask_names_it_and_tls_needs_its_certificates(certs, tmp_path):
    assert cluster.scheduler_of(None) is None
    assert cluster.scheduler_of('tcp://lab-1:8786') == cluster.Scheduler('tcp://lab-1:8786')
    assert cluster.scheduler_of('tls://lab-1:8786', str(certs)) == cluster.Scheduler('tls://lab-1:8786', str(certs))
    for address, tls, message in (
            ('lab-1:8786', None, 'expected tcp://HOST:PORT or tls://HOST:PORT'),
            ('http://lab-1:8786', None, 'expected tcp://HOST:PORT'),
            ('tcp://lab-1', None, 'expected tcp://HOST:PORT'),
            ('tls://lab-1:8786', None, 'a tls:// scheduler needs --tls DIR'),
            ('tcp://lab-1:8786', str(certs), 'is plain tcp://; name it tls://lab-1:8786'),
            ('tls://lab-1:8786', str(tmp_path), 'no ca.pem, client.pem, client.key in it'),
            (None, str(certs), 'certificates are for a scheduler of yours')):
        with pytest.raises(cluster.ClusterError, match=message):
            cluster.scheduler_of(address, tls)


def test_a_plain_scheduler_off_loopback_is_warned_of_once():
    said = io.StringIO()
    for address in ('tcp://127.0.0.1:8786', 'tcp://localhost:8786', 'tcp://[::1]:8786', 'tls://10.0.0.5:8786'):
        cluster.warn_if_open(cluster.Scheduler(address), said)
    assert said.getvalue() == ''
    for _ in range(3):
        cluster.warn_if_open(cluster.Scheduler('tcp://10.0.0.5:8786'), said)
    assert said.getvalue().count('\n') == 1 and 'any host that reaches port 8786 can run code' in said.getvalue()


def test_the_ca_signs_each_role_for_both_ends_with_the_hosts_named(certs):
    for role in certificates.ROLES:
        check = subprocess.run(['openssl', 'verify', '-CAfile', str(certs / 'ca.pem'), str(certs / (role + '.pem'))],
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
        assert check.returncode == 0 and ': OK' in check.stdout, check.stdout
        text = subprocess.run(['openssl', 'x509', '-in', str(certs / (role + '.pem')), '-noout', '-text'],
                              stdout=subprocess.PIPE, universal_newlines=True, check=True).stdout
        assert 'DNS:lab-1' in text and 'IP Address:10.0.0.5' in text and 'IP Address:127.0.0.1' in text, text
        assert 'TLS Web Server Authentication' in text and 'TLS Web Client Authentication' in text
        assert os.stat(str(certs / (role + '.key'))).st_mode & 0o077 == 0          # the owner's alone
        # What Dask's TLS does with them: a context that presents the role's pair and requires the CA's.
        context = ssl.create_default_context(ssl.Purpose.CLIENT_AUTH, cafile=str(certs / 'ca.pem'))
        context.load_cert_chain(str(certs / (role + '.pem')), str(certs / (role + '.key')))
    assert os.stat(str(certs / 'ca.key')).st_mode & 0o077 == 0


def test_certificates_already_there_are_left_alone(certs, capsys):
    before = (certs / 'client.pem').read_bytes()
    assert certificates.main([str(certs)]) == 2
    err = capsys.readouterr().err
    assert 'already holds ca.pem' in err and err.count('\n') == 1, err
    assert (certs / 'client.pem').read_bytes() == before
    assert certificates.main([str(certs / 'more'), '--days', '0']) == 2
    assert '--days: expected 1 to' in capsys.readouterr().err
