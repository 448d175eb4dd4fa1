"""Certificates for a Dask cluster only you can use: a CA, and a certificate and key each for the scheduler, the
workers and the client, signed by it (Dask's TLS then authenticates both ends of every connection).

    rosrun closed_loop certificates DIR [--host lab-1 --host 10.0.0.5] [--days 365]

writes ``DIR/ca.pem`` and ``DIR/ca.key`` (the CA: keep its key to yourself), and ``DIR/scheduler.pem``,
``DIR/scheduler.key``, ``DIR/worker.pem``, ``DIR/worker.key``, ``DIR/client.pem``, ``DIR/client.key``. Copy
``ca.pem`` and a role's pair to each machine of that role; ``--tls DIR`` of a sweep command reads ``ca.pem``,
``client.pem`` and ``client.key``. Keys are EC (P-256), readable by their owner only; each certificate names the
hosts given (and localhost) and serves for both ends of a connection. Files already there are left alone: the
command refuses, naming them. With the ``cryptography`` package (Debian's ``python3-cryptography``).
"""
import datetime
import ipaddress
import os
import sys

from closed_loop import cli

ROLES = ('scheduler', 'worker', 'client')
DAYS = 365
MAX_DAYS = 3650


def _backend():
    """cryptography's backend, which its releases before 3.1 (Ubuntu 20.04's 2.8) must be given."""
    from cryptography.hazmat.backends import default_backend
    return default_backend()


def _names(hosts):
    from cryptography import x509
    names = []
    for host in ['localhost', '127.0.0.1'] + list(hosts):
        try:
            name = x509.IPAddress(ipaddress.ip_address(host))
        except ValueError:
            name = x509.DNSName(host)
        if name not in names:
            names.append(name)
    return names


def _certificate(subject, key, issuer, issuer_key, days, ca, hosts=()):
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes
    from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID
    now = datetime.datetime.now(datetime.timezone.utc).replace(tzinfo=None)
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, subject)])
    builder = (x509.CertificateBuilder().subject_name(name).issuer_name(issuer or name).public_key(key.public_key())
               .serial_number(x509.random_serial_number()).not_valid_before(now - datetime.timedelta(minutes=5))
               .not_valid_after(now + datetime.timedelta(days=days))
               .add_extension(x509.BasicConstraints(ca=ca, path_length=0 if ca else None), critical=True))
    if ca:
        builder = builder.add_extension(x509.KeyUsage(True, False, False, False, False, True, True, False, False),
                                        critical=True)
    else:
        builder = builder.add_extension(x509.SubjectAlternativeName(_names(hosts)), critical=False).add_extension(
            x509.ExtendedKeyUsage([ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]), critical=False)
    return builder.sign(issuer_key or key, hashes.SHA256(), _backend())


def _write(path, data, private):
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600 if private else 0o644)
    with os.fdopen(fd, 'wb') as f:
        f.write(data)


def make(folder, hosts=(), days=DAYS):
    """Write the CA and the three pairs into ``folder`` (made if missing); returns the paths written. Raises
    FileExistsError naming the files already there (nothing is written then)."""
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    os.makedirs(folder, exist_ok=True)
    names = ['ca.pem', 'ca.key'] + ['%s.%s' % (role, ext) for role in ROLES for ext in ('pem', 'key')]
    there = [n for n in names if os.path.lexists(os.path.join(folder, n))]
    if there:
        raise FileExistsError('%s: already holds %s; choose another folder or remove them' % (folder, ', '.join(there)))
    ca_key = ec.generate_private_key(ec.SECP256R1(), _backend())
    ca = _certificate('closed_loop cluster CA', ca_key, None, None, days, True)
    pem = serialization.Encoding.PEM

    def key_bytes(key):
        return key.private_bytes(pem, serialization.PrivateFormat.PKCS8, serialization.NoEncryption())
    written = []
    for name, data, private in [('ca.pem', ca.public_bytes(pem), False), ('ca.key', key_bytes(ca_key), True)] + [
            item for role in ROLES for item in _pair(role, ca, ca_key, hosts, days, key_bytes)]:
        _write(os.path.join(folder, name), data, private)
        written.append(os.path.join(folder, name))
    return written


def _pair(role, ca, ca_key, hosts, days, key_bytes):
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    key = ec.generate_private_key(ec.SECP256R1(), _backend())
    cert = _certificate('closed_loop %s' % role, key, ca.subject, ca_key, days, False, hosts)
    return [('%s.pem' % role, cert.public_bytes(serialization.Encoding.PEM), False),
            ('%s.key' % role, key_bytes(key), True)]


def main(argv=None):
    parser = cli.parser('certificates', 'Write a CA and a certificate and key for a Dask scheduler, its workers and a '
                        'client (TLS with mutual authentication).')
    parser.add_argument('folder', help='where to write them (made if missing)')
    parser.add_argument('--host', action='append', default=[], help='a name or address the scheduler and workers '
                        'are reached by (repeat it; localhost and 127.0.0.1 are always in; default: none)')
    parser.add_argument('--days', type=int, default=DAYS, help='how long the certificates hold')
    args = parser.parse_args(argv)
    if not 1 <= args.days <= MAX_DAYS:
        print('certificates: --days: expected 1 to %d, got %d' % (MAX_DAYS, args.days), file=sys.stderr)
        return 2
    try:
        written = make(args.folder, args.host, args.days)
    except (FileExistsError, ValueError) as error:
        print('certificates: %s' % error, file=sys.stderr)
        return 2
    except OSError as error:
        print('certificates: %s: %s' % (args.folder, error.strerror or error), file=sys.stderr)
        return 2
    print('certificates: wrote %s' % ', '.join(os.path.basename(p) for p in written))
    print('certificates: keep ca.key to yourself; give each machine ca.pem and its role\'s pair')
    return 0


if __name__ == '__main__':
    sys.exit(main())
