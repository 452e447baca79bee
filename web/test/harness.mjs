// Test harness: starts the real release server on a free port and Debian's headless Chromium
// (playwright-core, never a downloaded browser).
import { spawn } from 'node:child_process';
import { mkdirSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = dirname(fileURLToPath(import.meta.url));
export const webDir = resolve(here, '..');
export const repoDir = resolve(webDir, '..');
export const artifacts = join(webDir, 'test-artifacts');
mkdirSync(artifacts, { recursive: true });

export const binary = process.env.COIFFURE_BIN ?? join(process.env.CARGO_TARGET_DIR ?? join(repoDir, 'target'), 'release', 'coiffure');
const chromiumPath = process.env.CHROMIUM ?? '/usr/bin/chromium';

/** Starts `coiffure serve --port 0 ...extra`; resolves with { url, proc, output() } once it listens. */
export function startServer(extra = []) {
  return new Promise((resolveStart, reject) => {
    const proc = spawn(binary, ['serve', '--port', '0', '--web', join(webDir, 'dist'), ...extra], { cwd: repoDir, stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    let err = '';
    const timer = setTimeout(() => reject(new Error(`server did not start within 120 s:\n${out}\n${err}`)), 120_000);
    proc.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/listening on (http:\/\/[^ ]+)/);
      if (m) {
        clearTimeout(timer);
        resolveStart({ url: m[1], proc, output: () => out, errors: () => err });
      }
    });
    proc.stderr.on('data', (d) => { err += d; });
    proc.on('error', (e) => { clearTimeout(timer); reject(new Error(`cannot run ${binary}: ${e.message} (build it with cargo build --release -p coiffure-server)`)); });
    proc.on('exit', (code) => { clearTimeout(timer); reject(new Error(`server exited with ${code} before listening:\n${out}\n${err}`)); });
  });
}

/** Stops the server with SIGINT (graceful: it prints its statistics) and returns its stdout. */
export function stopServer(server) {
  return new Promise((res) => {
    server.proc.removeAllListeners('exit');
    server.proc.on('exit', () => res(server.output()));
    server.proc.kill('SIGINT');
    setTimeout(() => { server.proc.kill('SIGKILL'); }, 10_000);
  });
}

export async function launchBrowser() {
  return chromium.launch({
    executablePath: chromiumPath,
    headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic'],
    // playwright gives every launch a fresh temporary profile (the --user-data-dir of ENVIRONMENT.md).
  });
}

/** Opens the viewer and waits until the scene is loaded and a few frames have been drawn (and received).
 * `view` (optional): the camera view (`?view=`, CAMERA_VIEWS in web/src/scene.ts; the default is the
 * three-quarter portrait). `drawn` (default 3): frames the page must have drawn; a second page in the same
 * software-rendered browser shares its CPU with the first, so a test of the protocol alone may ask for 0. */
export async function openViewer(browser, url, { view, drawn = 3 } = {}) {
  const page = await browser.newPage({ viewport: { width: 1024, height: 720 } });
  if (view) { const u = new URL(url); u.searchParams.set('view', view); url = u.href; }
  // Software rendering is slow (seconds per frame for the default scene): generous timeouts.
  page.setDefaultTimeout(180_000);
  const logs = [];
  page.on('console', (m) => logs.push(m.text()));
  page.on('pageerror', (e) => logs.push(`pageerror: ${e.message}`));
  await page.goto(url, { waitUntil: 'domcontentloaded' });
  await page.waitForFunction((n) => window.coiffure && window.coiffure.sceneLoaded && window.coiffure.framesRendered >= n && window.coiffure.framesReceived > 2, drawn, { timeout: 120_000, polling: 100 });
  return { page, logs };
}

/** Drags with the left button from world point a to world point b in `steps` steps (ms between steps);
 * `onStep(i)` (optional) is called after step i and awaited. The viewer draws nothing during the drag
 * (`coiffureDebug.holdFrames`; the session, its messages and the poses go on): in software rendering a real
 * pointer move waits for the next frame (1-3 s for 5k strands), which made a drag of 40 steps at 50 ms (2 s)
 * last 1-2 minutes. A screenshot during the drag belongs in `onStep`, taken with `screenshotDrawn`. */
export async function dragWorld(page, a, b, steps = 40, pause = 30, onStep = null) {
  const pa = await page.evaluate((p) => window.coiffureDebug.project(...p), a);
  const pb = await page.evaluate((p) => window.coiffureDebug.project(...p), b);
  await page.evaluate(() => window.coiffureDebug.holdFrames(true));
  try {
    await page.mouse.move(pa[0], pa[1]);
    await page.mouse.down();
    for (let i = 1; i <= steps; i++) {
      const t = i / steps;
      await page.mouse.move(pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1]));
      if (onStep) await onStep(i);
      await page.waitForTimeout(pause);
    }
    await page.mouse.up();
  } finally {
    await page.evaluate(() => window.coiffureDebug.holdFrames(false));
  }
}

/** A screenshot of a frame drawn now while the viewer holds its frames (during `dragWorld`): drawing resumes
 * until a frame has been drawn with the current state, the screenshot is taken, and the frames are held again. */
export async function screenshotDrawn(page, path) {
  const n = await page.evaluate(() => { window.coiffureDebug.holdFrames(false); return window.coiffure.framesRendered; });
  await page.waitForFunction((k) => window.coiffure.framesRendered > k, n, { polling: 50 });
  await page.screenshot({ path });
  await page.evaluate(() => window.coiffureDebug.holdFrames(true));
}

/** A stroke at a hand's pace whatever the frame rate: the pointer over world point a for `hoverMs`, the left
 * button pressed there (real pointer events) for `pressMs`, then the pointer moved to b over `seconds` by moves dispatched to the viewer's canvas from a
 * timer in the page at `hz` (the viewer's own pointer handlers, which send a POSE each), then released at b. In
 * software rendering a real pointer move waits for the next frame (0.5-1.3 s), so a stroke of page.mouse
 * moves goes at a few mm/s, and a frame or a screenshot can stop the page's timers for seconds: the viewer
 * draws nothing during the moves (`coiffureDebug.holdFrames`; the session, its messages and the viewer's
 * pseudo-haptics go on), and a screenshot belongs in `beforeRelease`, awaited with the tool still pressed at b. Resolves with the moves dispatched, the stroke's duration (ms) and the largest
 * gap between moves (ms), as the page timed them. */
export async function strokeWorld(page, a, b, seconds, hz = 100, { hoverMs = 1500, pressMs = 400, beforeRelease = null } = {}) {
  const pa = await page.evaluate((p) => window.coiffureDebug.project(...p), a);
  const pb = await page.evaluate((p) => window.coiffureDebug.project(...p), b);
  // As a hand: over a first (the tool comes to it, `hoverMs`), pressed into the hair there (`pressMs`), then drawn.
  await page.mouse.move(pa[0], pa[1]);
  await page.waitForTimeout(hoverMs);
  await page.mouse.down();
  await page.waitForTimeout(pressMs);
  // The viewer draws nothing during the moves: a software-rendered frame can stall the page for seconds.
  await page.evaluate(() => window.coiffureDebug.holdFrames(true));
  const timing = await page.evaluate(({ pa, pb, seconds, hz }) => new Promise((done) => {
    const canvas = document.getElementById('view');
    const t0 = performance.now();
    let moves = 0, last = t0, gap = 0, frames = window.coiffure.framesReceived, frameJump = 0;
    const tick = () => {
      const now = performance.now();
      const t = Math.min(1, (now - t0) / (1000 * seconds));
      canvas.dispatchEvent(new PointerEvent('pointermove', { bubbles: true, pointerId: 1, pointerType: 'mouse', isPrimary: true, buttons: 1,
        clientX: pa[0] + t * (pb[0] - pa[0]), clientY: pa[1] + t * (pb[1] - pa[1]) }));
      moves++;
      // FRAMEs handled since the last move (a page that falls behind used to find a backlog of stale ones).
      frameJump = Math.max(frameJump, window.coiffure.framesReceived - frames);
      frames = window.coiffure.framesReceived;
      gap = Math.max(gap, now - last);
      last = now;
      if (t < 1) setTimeout(tick, 1000 / hz); else done({ moves, ms: now - t0, maxGapMs: gap, maxFramesPerMove: frameJump });
    };
    tick();
  }), { pa, pb, seconds, hz });
  await page.evaluate(() => window.coiffureDebug.holdFrames(false));
  await page.mouse.move(pb[0], pb[1]);
  if (beforeRelease) await beforeRelease();
  await page.mouse.up();
  return timing;
}
