#!/usr/bin/env python3
"""The README's two commands on a bare Debian bookworm, as a new user's machine has it: ``make fresh``.

Makes a minimal bookworm root with Debian's debootstrap (variant minbase, as the usual Debian container image,
plus git, make and ca-certificates) from the Debian archive this machine's apt already uses; clones this
repository's committed HEAD into it at /root/project; and there, as root, runs ``make demo`` and then
``make test`` with nothing in the environment but HOME, PATH and TERM. Each runs in mount and PID namespaces of
its own (its own /proc, /sys, /dev/shm and /run), so nothing it mounts or starts outlives it. Prints each
command's result and time, and exits non-zero if either failed.

What the root gets from this machine, and why: its Debian archive (the mirror and suites apt uses here), its
name servers (/etc/resolv.conf), and the certificate authorities this machine trusts beyond Debian's own set
(a network that inspects TLS, such as this one's, would otherwise refuse pip's downloads). Downloads are kept
in ``DIR/cache`` between runs (``--no-cache`` to fetch everything again); what is installed is not.

Usage, as root (nothing a user types reaches a shell):
    make fresh [FRESH_ARGS="[demo] [test] [--dir DIR] [--ref REF] [--keep] [--no-cache]"]
"""
import argparse
import os
import shutil
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
SUITE = 'bookworm'
#: What the issue's bare machine has beyond debootstrap's minimal system.
INCLUDE = ('git', 'make', 'ca-certificates')
#: The only variables the commands see: a user's shell as root on a new machine.
PLAIN_PATH = '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin'
PROJECT = '/root/project'
TARGETS = ('demo', 'test')
HOSTS = '127.0.0.1\tlocalhost\n::1\t\tlocalhost ip6-localhost ip6-loopback\n'
#: (cache folder under DIR/cache, where it is mounted in the root) while the commands run.
CACHES = (('apt', 'var/cache/apt/archives'), ('pip', 'root/.cache/pip'))


class FreshError(RuntimeError):
    pass


def say(text):
    print('fresh: %s' % text, flush=True)


def minutes(seconds):
    return '%dm%02ds' % divmod(int(round(seconds)), 60)


def run(argv, log=None, **kwargs):
    """Run ``argv`` (a list: no shell), its output to ``log`` (a path) or to ours; FreshError if it fails."""
    if log is None:
        done = subprocess.run(argv, **kwargs)
    else:
        with open(log, 'a') as out:
            done = subprocess.run(argv, stdout=out, stderr=subprocess.STDOUT, **kwargs)
    if done.returncode != 0:
        raise FreshError('%s failed (exit %d)%s' % (argv[0], done.returncode, ', log: %s' % log if log else ''))
    return done


def debian_archive():
    """(mirror of the suite itself, [(site, suite)] of every Debian bookworm suite apt uses here)."""
    out = subprocess.run(['apt-get', 'indextargets', '--release-info', 'Created-By: Packages', 'Origin: Debian'],
                         stdout=subprocess.PIPE, universal_newlines=True, check=True).stdout
    suites = []
    for record in out.split('\n\n'):
        fields = dict(line.split(': ', 1) for line in record.splitlines() if ': ' in line)
        suite = fields.get('Release', '')
        if fields.get('Target-Of') == 'deb' and suite.split('-')[0] == SUITE and fields.get('Component') == 'main':
            if (fields['Site'], suite) not in suites:
                suites.append((fields['Site'], suite))
    mirrors = [site for site, suite in suites if suite == SUITE]
    if not mirrors:
        raise FreshError("this machine's apt uses no Debian %s archive (apt-get indextargets finds none); "
                         'fresh makes the root from the archive apt already uses' % SUITE)
    return mirrors[0], suites


def certificates(path):
    """The PEM certificates in a bundle file, in order, as text."""
    if not os.path.exists(path):
        return []
    with open(path) as f:
        text = f.read()
    end = '-----END CERTIFICATE-----'
    return [block.strip()[block.strip().index('-----BEGIN'):] + '\n' + end + '\n'
            for block in text.split(end) if '-----BEGIN CERTIFICATE-----' in block]


def mounts_under(folder):
    """Mount points at or under ``folder`` in this mount namespace (none may be there when it is removed)."""
    found = []
    with open('/proc/self/mountinfo') as f:
        for line in f:
            point = line.split()[4].replace('\\040', ' ')
            if point == folder or point.startswith(folder.rstrip('/') + '/'):
                found.append(point)
    return found


def remove_root(root):
    if not os.path.exists(root):
        return
    left = mounts_under(root)
    if left:
        raise FreshError('%s still has mounts (%s): not removed; unmount them first' % (root, ', '.join(left)))
    run(['rm', '-rf', '--one-file-system', '--', root])


def make_root(root, cache, log, use_cache):
    mirror, suites = debian_archive()
    say('debootstrap %s (minbase, with %s) from %s into %s' % (SUITE, ', '.join(INCLUDE), mirror, root))
    started = time.monotonic()
    argv = ['debootstrap', '--variant=minbase', '--include=' + ','.join(INCLUDE)]
    if use_cache:
        os.makedirs(os.path.join(cache, 'debootstrap'), exist_ok=True)
        argv.append('--cache-dir=' + os.path.join(cache, 'debootstrap'))
    run(argv + [SUITE, root, mirror], log=log)
    say('a bare %s root in %s' % (SUITE, minutes(time.monotonic() - started)))
    with open(os.path.join(root, 'etc', 'apt', 'sources.list'), 'w') as f:
        f.writelines('deb %s %s main\n' % (site, suite) for site, suite in suites)
    shutil.copyfile('/etc/resolv.conf', os.path.join(root, 'etc', 'resolv.conf'), follow_symlinks=True)
    with open(os.path.join(root, 'etc', 'hosts'), 'w') as f:
        f.write(HOSTS)
    theirs = set(certificates(os.path.join(root, 'etc', 'ssl', 'certs', 'ca-certificates.crt')))
    extra = [pem for pem in certificates('/etc/ssl/certs/ca-certificates.crt') if pem not in theirs]
    if extra:
        folder = os.path.join(root, 'usr', 'local', 'share', 'ca-certificates')
        for number, pem in enumerate(extra):
            with open(os.path.join(folder, 'this-machine-%d.crt' % number), 'w') as f:
                f.write(pem)
        run(['chroot', root, 'update-ca-certificates'], log=log)
        say('the root trusts %d certificate authorit%s this machine trusts beyond Debian\'s set'
            % (len(extra), 'y' if len(extra) == 1 else 'ies'))


def clone(root, ref):
    head = subprocess.run(['git', '-C', ROOT, 'rev-parse', '--verify', ref + '^{commit}'], stdout=subprocess.PIPE,
                          universal_newlines=True)
    if head.returncode != 0:
        raise FreshError('%s is not a commit of %s' % (ref, ROOT))
    commit = head.stdout.strip()
    dirty = subprocess.run(['git', '-C', ROOT, 'status', '--porcelain', '--untracked-files=no'],
                           stdout=subprocess.PIPE, universal_newlines=True).stdout.strip()
    if dirty:
        say('note: changes not committed in %s are not in the clone' % ROOT)
    target = os.path.join(root, PROJECT.lstrip('/'))
    run(['git', 'clone', '--quiet', '--no-hardlinks', '--', ROOT, target])
    run(['git', '-C', target, 'checkout', '--quiet', '--detach', commit])
    say('cloned %s at %s into %s' % (ROOT, commit[:12], PROJECT))


def run_inside(root, cache, target, log):
    """``make TARGET`` in the root, in new mount and PID namespaces; its output to ours and to ``log``.
    Returns (exit status, wall seconds, its last lines)."""
    argv = ['unshare', '--mount', '--propagation', 'private', '--pid', '--fork', '--kill-child',
            sys.executable, os.path.abspath(__file__), '--inside', root, '--cache', cache or '', target]
    started = time.monotonic()
    tail = []
    with open(log, 'w') as out:
        process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        for raw in process.stdout:
            line = raw.decode(errors='replace')
            out.write(line)
            sys.stdout.write('  | ' + line)
            sys.stdout.flush()
            tail = (tail + [line.rstrip('\n')])[-40:]
        code = process.wait()
    return code, time.monotonic() - started, tail


def inside(root, cache, target):
    """In the new namespaces (as PID 1 of its PID namespace): mount what a running system has, enter the root,
    and run ``make TARGET`` in /root/project with a plain environment, reaping every orphan until it ends."""
    def mount(*argv):
        subprocess.run(['mount'] + list(argv), check=True)
    at = lambda *parts: os.path.join(root, *parts)  # noqa: E731
    # The root a mount of its own, as / is on any machine: `unshare --propagation` and `ip netns exec` change
    # the propagation of /, which only a mount point has.
    mount('--bind', root, root)
    mount('-t', 'proc', 'proc', at('proc'))
    mount('-t', 'sysfs', 'sysfs', at('sys'))
    mount('--rbind', '/dev', at('dev'))
    mount('-t', 'tmpfs', '-o', 'mode=1777', 'tmpfs', at('dev', 'shm'))
    mount('-t', 'tmpfs', '-o', 'mode=755', 'tmpfs', at('run'))
    if cache:
        for name, where in CACHES:
            os.makedirs(os.path.join(cache, name), exist_ok=True)
            os.makedirs(at(where), exist_ok=True)
            mount('--bind', os.path.join(cache, name), at(where))
    os.chroot(root)
    os.chdir(PROJECT)
    env = {'HOME': '/root', 'PATH': PLAIN_PATH, 'TERM': os.environ.get('TERM') or 'dumb'}
    child = os.fork()
    if child == 0:
        try:
            os.execve('/usr/bin/make', ['make', target], env)
        finally:
            os._exit(127)
    while True:
        pid, status = os.wait()
        if pid == child:
            return os.waitstatus_to_exitcode(status)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('targets', nargs='*', metavar='demo|test',
                        help='the make targets to run in the root, in this order (default: demo, then test)')
    parser.add_argument('--dir', default=os.path.join(ROOT, '.fresh'),
                        help='where the root (DIR/root), the download caches and the logs go (default: .fresh in this '
                        'repository, which git ignores)')
    parser.add_argument('--ref', default='HEAD', help='the commit of this repository to clone (default: HEAD)')
    parser.add_argument('--keep', action='store_true', help='keep the root afterwards (it is removed by default)')
    parser.add_argument('--no-cache', action='store_true', help='download everything again')
    parser.add_argument('--inside', help=argparse.SUPPRESS)
    parser.add_argument('--cache', help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.inside:
        return inside(args.inside, args.cache, args.targets[0])
    targets = args.targets or ['demo', 'test']
    if set(targets) - set(TARGETS):
        parser.error('targets are %s, not %s' % (' and '.join(TARGETS), ', '.join(sorted(set(targets) - set(TARGETS)))))
    if os.geteuid() != 0:
        print('fresh: needs root (debootstrap, chroot and namespaces)', file=sys.stderr)
        return 2
    folder = os.path.abspath(args.dir)
    root, cache = os.path.join(folder, 'root'), os.path.join(folder, 'cache')
    use_cache = not args.no_cache
    os.makedirs(folder, exist_ok=True)
    results = []
    try:
        if shutil.which('debootstrap') is None:
            say('installing debootstrap')
            run(['apt-get', 'update', '-qq'])
            run(['apt-get', 'install', '-y', '-qq', '--no-install-recommends', 'debootstrap'],
                env=dict(os.environ, DEBIAN_FRONTEND='noninteractive'))
        remove_root(root)
        log = os.path.join(folder, 'debootstrap.log')
        if os.path.exists(log):
            os.remove(log)
        make_root(root, cache, log, use_cache)
        clone(root, args.ref)
        for target in targets:
            say('make %s (in %s, environment HOME, PATH and TERM only)' % (target, PROJECT))
            log = os.path.join(folder, 'make-%s.log' % target)
            code, seconds, tail = run_inside(root, cache if use_cache else '', target, log)
            closing = [line for line in tail if line.startswith('tests: ')]
            results.append((target, code, seconds, closing[-1] if closing else '', log))
    except (FreshError, OSError, subprocess.CalledProcessError) as error:
        print('fresh: %s' % error, file=sys.stderr)
        return 1
    finally:
        if not args.keep:
            try:
                remove_root(root)
            except FreshError as error:
                print('fresh: %s' % error, file=sys.stderr)
    for target, code, seconds, closing, log in results:
        say('make %s: %s in %s%s (log: %s)' % (target, 'passed' if code == 0 else 'FAILED (exit %d)' % code,
                                               minutes(seconds), ': ' + closing if closing else '', log))
    return 0 if results and all(code == 0 for _, code, _, _, _ in results) else 1


if __name__ == '__main__':
    sys.exit(main())
