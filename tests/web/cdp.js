// cdp.js — a small Chrome DevTools Protocol client for headless Chromium.
//
// Starts Debian's chromium with --remote-debugging-pipe: the browser reads
// protocol messages on its fd 3 and writes them on its fd 4, each message
// one JSON text ended by a NUL byte.  Node's child_process gives those two
// fds as pipes, so no WebSocket library (and no npm package) is needed.
//
//   const cdp = require('./cdp');
//   const b = await cdp.launch({ timeoutMs: 60000 });
//   const page = await b.newPage('file:///tmp/p.html');
//   const v = await page.eval('1 + 1');
//   await b.close();
//
// Every command gives up after timeoutMs (default 30 s) with an error
// naming it, and the browser is killed after the whole run's limit, so a
// test using this never hangs.
'use strict';

const { spawn } = require('child_process');
const fs = require('fs');
const os = require('os');
const path = require('path');

function findChromium() {
    for (const name of ['chromium', 'chromium-browser', 'google-chrome']) {
        for (const dir of (process.env.PATH || '/usr/bin').split(':')) {
            const p = path.join(dir, name);
            try {
                fs.accessSync(p, fs.constants.X_OK);
                return p;
            } catch (e) { /* next */ }
        }
    }
    return null;
}

class PageLink {
    constructor(browser, sessionId, targetId) {
        this.browser = browser;
        this.id = sessionId;
        this.targetId = targetId;
    }
    send(method, params) { return this.browser.send(method, params, this.id); }
    on(method, fn) { this.browser.listen(this.id, method, fn); }
    // Waits for one event of this link (its params), or throws after ms.
    waitFor(method, ms) { return this.browser.waitFor(this.id, method, ms); }

    // The value of a JavaScript expression in the page (promises awaited);
    // a thrown exception becomes an Error with the page's message.
    async eval(expr, timeoutMs) {
        const r = await this.browser.send('Runtime.evaluate', {
            expression: expr, awaitPromise: true, returnByValue: true,
        }, this.id, timeoutMs);
        if (r.exceptionDetails) {
            const d = r.exceptionDetails;
            const msg = (d.exception && (d.exception.description || d.exception.value)) || d.text;
            throw new Error('page: ' + msg);
        }
        return r.result.value;
    }

    // Goes to url and waits for its load event.
    async goto(url, timeoutMs) {
        const loaded = this.waitFor('Page.loadEventFired', timeoutMs || this.browser.timeoutMs);
        const r = await this.send('Page.navigate', { url });
        if (r.errorText) throw new Error('navigate ' + url + ': ' + r.errorText);
        await loaded;
    }

    // The centre and size of the element selector matches, in CSS pixels
    // of the viewport (after scrolling it into view).
    async box(selector) {
        const r = await this.eval(`(() => {
            const e = document.querySelector(${JSON.stringify(selector)});
            if (!e) return null;
            e.scrollIntoView({block: 'center', inline: 'center'});
            const b = e.getBoundingClientRect();
            return {x: b.left, y: b.top, w: b.width, h: b.height};
        })()`);
        if (!r) throw new Error('no element ' + selector + ' in the page');
        return r;
    }

    // Real mouse events: press at (x0,y0), steps moves, release at (x1,y1).
    async drag(x0, y0, x1, y1, steps) {
        const n = steps || 8;
        const m = (type, x, y, buttons) => this.send('Input.dispatchMouseEvent', {
            type, x, y, button: 'left', buttons, clickCount: type === 'mouseMoved' ? 0 : 1,
        });
        await this.send('Input.dispatchMouseEvent', { type: 'mouseMoved', x: x0, y: y0, button: 'none', buttons: 0 });
        await m('mousePressed', x0, y0, 1);
        for (let i = 1; i <= n; ++i) await m('mouseMoved', x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n, 1);
        await m('mouseReleased', x1, y1, 0);
    }

    async click(x, y) {
        await this.send('Input.dispatchMouseEvent', { type: 'mouseMoved', x, y, button: 'none', buttons: 0 });
        await this.send('Input.dispatchMouseEvent', { type: 'mousePressed', x, y, button: 'left', buttons: 1, clickCount: 1 });
        await this.send('Input.dispatchMouseEvent', { type: 'mouseReleased', x, y, button: 'left', buttons: 0, clickCount: 1 });
    }

    // A PNG of the viewport written to file.
    async screenshot(file) {
        const r = await this.send('Page.captureScreenshot', { format: 'png' });
        fs.mkdirSync(path.dirname(file), { recursive: true });
        fs.writeFileSync(file, Buffer.from(r.data, 'base64'));
        return file;
    }

    // Sets the files of an <input type=file> (selector) and lets the page
    // see the change as if the user had picked them.
    async setFiles(selector, files) {
        const doc = await this.send('DOM.getDocument', { depth: 0 });
        const q = await this.send('DOM.querySelector', { nodeId: doc.root.nodeId, selector });
        if (!q.nodeId) throw new Error('no element ' + selector + ' in the page');
        await this.send('DOM.setFileInputFiles', { nodeId: q.nodeId, files });
    }
}

class Browser {
    constructor(proc, opts) {
        this.proc = proc;
        this.timeoutMs = opts.timeoutMs || 30000;
        this.nextId = 1;
        this.pending = new Map();
        this.listeners = [];
        this.buf = Buffer.alloc(0);
        this.closed = false;
        this.stderr = '';
        this.exitError = null;
        const input = proc.stdio[4];
        input.on('data', (chunk) => this.onData(chunk));
        proc.stderr.on('data', (d) => {
            if (this.stderr.length < 65536) this.stderr += d.toString();
        });
        proc.on('exit', (code, sig) => {
            this.closed = true;
            this.exitError = new Error(`chromium ended (exit ${code}, signal ${sig})` +
                (this.stderr ? ': ' + this.stderr.slice(-600) : ''));
            for (const p of this.pending.values()) p.reject(this.exitError);
            this.pending.clear();
        });
        proc.stdio[3].on('error', () => { /* the exit handler reports it */ });
    }

    onData(chunk) {
        this.buf = Buffer.concat([this.buf, chunk]);
        let z;
        while ((z = this.buf.indexOf(0)) >= 0) {
            const text = this.buf.subarray(0, z).toString('utf8');
            this.buf = this.buf.subarray(z + 1);
            let msg;
            try {
                msg = JSON.parse(text);
            } catch (e) {
                continue;
            }
            if (msg.id !== undefined && this.pending.has(msg.id)) {
                const p = this.pending.get(msg.id);
                this.pending.delete(msg.id);
                if (msg.error) p.reject(new Error(`${p.method}: ${msg.error.message}${msg.error.data ? ' (' + msg.error.data + ')' : ''}`));
                else p.resolve(msg.result);
            } else if (msg.method) {
                for (const l of this.listeners.slice()) {
                    if (l.method === msg.method && (l.link === undefined || l.link === msg.sessionId)) l.fn(msg.params);
                }
            }
        }
    }

    // Sends one command (to the browser, or to a page's link) and
    // resolves with its result; rejects on a protocol error or a timeout.
    send(method, params, sessionId, timeoutMs) {
        if (this.closed) return Promise.reject(this.exitError || new Error('browser closed'));
        const id = this.nextId++;
        const msg = { id, method, params: params || {} };
        if (sessionId) msg.sessionId = sessionId;
        const ms = timeoutMs || this.timeoutMs;
        return new Promise((resolve, reject) => {
            const timer = setTimeout(() => {
                this.pending.delete(id);
                reject(new Error(`${method}: no answer in ${ms} ms`));
            }, ms);
            this.pending.set(id, {
                method,
                resolve: (v) => { clearTimeout(timer); resolve(v); },
                reject: (e) => { clearTimeout(timer); reject(e); },
            });
            this.proc.stdio[3].write(JSON.stringify(msg) + '\0');
        });
    }

    listen(link, method, fn) { this.listeners.push({ link, method, fn }); }

    waitFor(link, method, ms) {
        return new Promise((resolve, reject) => {
            const l = { link, method, fn: null };
            const timer = setTimeout(() => {
                this.listeners = this.listeners.filter((x) => x !== l);
                reject(new Error(`${method}: not seen in ${ms} ms`));
            }, ms);
            l.fn = (params) => {
                clearTimeout(timer);
                this.listeners = this.listeners.filter((x) => x !== l);
                resolve(params);
            };
            this.listeners.push(l);
        });
    }

    // A new tab attached in flat mode, with Page, Runtime, DOM and Network
    // events on, at url (about:blank if none), sized width x height.
    async newPage(url, opts) {
        const o = opts || {};
        const { targetId } = await this.send('Target.createTarget', { url: 'about:blank' });
        const { sessionId } = await this.send('Target.attachToTarget', { targetId, flatten: true });
        const s = new PageLink(this, sessionId, targetId);
        s.console = [];
        s.exceptions = [];
        s.requests = [];
        s.on('Runtime.consoleAPICalled', (p) => s.console.push(p.type + ': ' + p.args.map((a) => a.value !== undefined ? a.value : a.description).join(' ')));
        s.on('Runtime.exceptionThrown', (p) => s.exceptions.push(p.exceptionDetails.exception ? p.exceptionDetails.exception.description : p.exceptionDetails.text));
        s.on('Network.requestWillBeSent', (p) => s.requests.push(p.request.url));
        await s.send('Page.enable');
        await s.send('Runtime.enable');
        await s.send('DOM.enable');
        await s.send('Network.enable');
        await s.send('Emulation.setDeviceMetricsOverride', {
            width: o.width || 1280, height: o.height || 900, deviceScaleFactor: 1, mobile: false,
        });
        if (o.offline) {
            await s.send('Network.emulateNetworkConditions', {
                offline: true, latency: 0, downloadThroughput: -1, uploadThroughput: -1,
            });
        }
        if (url) await s.goto(url);
        return s;
    }

    async close() {
        clearTimeout(this.killer);
        if (!this.closed) {
            try {
                await this.send('Browser.close', {}, undefined, 5000);
            } catch (e) { /* killed below */ }
        }
        await new Promise((resolve) => {
            if (this.closed) return resolve();
            const t = setTimeout(() => { try { this.proc.kill('SIGKILL'); } catch (e) { /* gone */ } resolve(); }, 5000);
            this.proc.on('exit', () => { clearTimeout(t); resolve(); });
        });
        running.delete(this);
        if (this.profile) fs.rmSync(this.profile, { recursive: true, force: true });
        this.profile = null;
    }
}

// The browsers still running: killed, and their profiles removed, when
// this process is stopped by a signal (a test's time limit) or exits.
const running = new Set();
function cleanup() {
    for (const b of running) {
        try { b.proc.kill('SIGKILL'); } catch (e) { /* gone */ }
        try { fs.rmSync(b.profile, { recursive: true, force: true }); } catch (e) { /* gone */ }
    }
    running.clear();
}
process.on('exit', cleanup);
for (const sig of ['SIGTERM', 'SIGINT', 'SIGHUP']) {
    process.on(sig, () => {
        cleanup();
        process.exit(1);
    });
}

// Starts headless chromium (opts.chromium or the first found on PATH) with
// a fresh profile and no background network traffic.  opts.proxy routes
// every request through that proxy (a dead one: nothing can leave);
// opts.lifeMs kills the browser after that long whatever happens.
async function launch(opts) {
    const o = opts || {};
    const exe = o.chromium || findChromium();
    if (!exe) throw new Error('chromium is not installed');
    const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'sidx-cdp-'));
    const args = [
        '--headless', '--remote-debugging-pipe', '--no-sandbox', '--disable-gpu',
        '--disable-dev-shm-usage', '--no-first-run', '--no-default-browser-check',
        '--disable-background-networking', '--disable-component-update', '--disable-sync',
        '--disable-default-apps', '--disable-extensions', '--disable-quic', '--hide-scrollbars',
        '--mute-audio',
        '--user-data-dir=' + profile,
    ];
    if (o.proxy) args.push('--proxy-server=' + o.proxy, '--proxy-bypass-list=<-loopback>');
    args.push('about:blank');
    const proc = spawn(exe, args, { stdio: ['ignore', 'ignore', 'pipe', 'pipe', 'pipe'] });
    const b = new Browser(proc, o);
    b.profile = profile;
    running.add(b);
    proc.on('exit', () => running.delete(b));
    b.killer = setTimeout(() => { try { proc.kill('SIGKILL'); } catch (e) { /* gone */ } }, o.lifeMs || 300000);
    b.killer.unref();
    await b.send('Browser.getVersion');
    return b;
}

module.exports = { launch, findChromium };
