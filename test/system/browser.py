"""A real headless browser for the tests: Debian's chromium, driven over the DevTools protocol on a pipe
(``--remote-debugging-pipe``: no port), in a network namespace of its own with no interface up (``unshare
--net``), so a page it opens can reach nothing beyond its files."""
import base64
import json
import os
import select
import shutil
import subprocess
import tempfile
import time

CHROMIUM = shutil.which('chromium') or shutil.which('chromium-browser')
FLAGS = ('--headless=new', '--no-sandbox', '--disable-gpu', '--no-first-run', '--no-default-browser-check',
         '--disable-background-networking', '--disable-component-update', '--disable-sync', '--disable-extensions',
         '--hide-scrollbars', '--remote-debugging-pipe')


class BrowserError(RuntimeError):
    pass


class Browser:
    """``with Browser() as b: page = b.open(url, width, height)``; then ``page.evaluate(js)``,
    ``page.screenshot(path)``, ``page.problems`` (console errors, uncaught exceptions, failed loads)."""

    def __init__(self, timeout_s=30.0):
        self.timeout_s = timeout_s
        if CHROMIUM is None:
            raise BrowserError('no chromium on PATH (make provision installs it)')
        self.profile = tempfile.mkdtemp(prefix='chromium-')
        to_child, self._to_browser = os.pipe()
        self._from_browser, from_child = os.pipe()
        high = [os.dup(fd) for fd in (to_child, from_child)]           # out of the way of fds 3 and 4

        def plumb():
            os.dup2(high[0], 3)
            os.dup2(high[1], 4)
        self.process = subprocess.Popen(['unshare', '--net', CHROMIUM, '--user-data-dir=' + self.profile] + list(FLAGS)
                                        + ['about:blank'], pass_fds=(3, 4) + tuple(high), preexec_fn=plumb,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for fd in (to_child, from_child) + tuple(high):
            os.close(fd)
        self._next_id, self._buffer, self.events = 0, b'', []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        try:
            self.send('Browser.close')
        except (BrowserError, OSError):
            pass
        try:
            self.process.wait(10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        for fd in (self._to_browser, self._from_browser):
            try:
                os.close(fd)
            except OSError:
                pass
        shutil.rmtree(self.profile, ignore_errors=True)

    def send(self, method, params=None, session=None):
        """Send a command and wait for its result (events meanwhile go to ``events``)."""
        self._next_id += 1
        message = {'id': self._next_id, 'method': method, 'params': params or {}}
        if session:
            message['sessionId'] = session
        os.write(self._to_browser, json.dumps(message).encode() + b'\0')
        deadline = time.monotonic() + self.timeout_s
        while True:
            reply = self._read(deadline)
            if reply.get('id') == self._next_id:
                if 'error' in reply:
                    raise BrowserError('%s: %s' % (method, reply['error']))
                return reply.get('result', {})
            self.events.append(reply)

    def wait_event(self, method, session, timeout_s=None):
        deadline = time.monotonic() + (timeout_s or self.timeout_s)
        while True:
            for event in self.events:
                if event.get('method') == method and event.get('sessionId') == session:
                    self.events.remove(event)
                    return event
            self.events.append(self._read(deadline))

    def _read(self, deadline):
        while b'\0' not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._from_browser], [], [], left)[0]:
                raise BrowserError('no answer from chromium within %.0f s' % self.timeout_s)
            chunk = os.read(self._from_browser, 1 << 20)
            if not chunk:
                raise BrowserError('chromium closed its pipe (exit %s)' % self.process.poll())
            self._buffer += chunk
        text, self._buffer = self._buffer.split(b'\0', 1)
        return json.loads(text)

    def open(self, url, width, height, mobile=False):
        target = self.send('Target.createTarget', {'url': 'about:blank'})['targetId']
        session = self.send('Target.attachToTarget', {'targetId': target, 'flatten': True})['sessionId']
        page = Page(self, session)
        for domain in ('Page', 'Runtime', 'Log'):
            self.send(domain + '.enable', session=session)
        self.send('Emulation.setDeviceMetricsOverride', {'width': width, 'height': height, 'deviceScaleFactor': 1,
                                                         'mobile': mobile}, session)
        self.send('Page.navigate', {'url': url}, session)
        self.wait_event('Page.loadEventFired', session)
        return page


class Page:
    def __init__(self, browser, session):
        self.browser, self.session = browser, session

    def evaluate(self, expression):
        result = self.browser.send('Runtime.evaluate', {'expression': expression, 'returnByValue': True,
                                                        'awaitPromise': True}, self.session)
        if 'exceptionDetails' in result:
            raise BrowserError('%s: %s' % (expression, result['exceptionDetails']))
        return result['result'].get('value')

    @property
    def problems(self):
        """What the page reported as wrong: uncaught exceptions, console errors and warnings, log errors (a file
        that would not load)."""
        found = []
        for event in self.browser.events:
            if event.get('sessionId') != self.session:
                continue
            method, params = event.get('method'), event.get('params', {})
            if method == 'Runtime.exceptionThrown':
                found.append('exception: %s' % params['exceptionDetails'].get('text'))
            elif method == 'Runtime.consoleAPICalled' and params.get('type') in ('error', 'warning', 'assert'):
                found.append('console.%s: %s' % (params['type'], [a.get('value') for a in params.get('args', [])]))
            elif method == 'Log.entryAdded' and params['entry'].get('level') in ('error', 'warning'):
                found.append('log %s: %s (%s)' % (params['entry']['level'], params['entry'].get('text'),
                                                  params['entry'].get('url')))
        return found

    def screenshot(self, path):
        """A PNG of the whole page (beyond the viewport) at ``path``."""
        size = self.browser.send('Page.getLayoutMetrics', session=self.session)['cssContentSize']
        shot = self.browser.send('Page.captureScreenshot', {'format': 'png', 'captureBeyondViewport': True, 'clip': {
            'x': 0, 'y': 0, 'width': size['width'], 'height': size['height'], 'scale': 1}}, self.session)
        with open(path, 'wb') as f:
            f.write(base64.b64decode(shot['data']))
