// End-to-end tests of `coiffure serve` and the viewer in headless Chromium (software WebGL2).
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFileSync, rmSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { artifacts, binary, dragWorld, launchBrowser, strokeWorld, openViewer, repoDir, screenshotDrawn, startServer, stopServer } from './harness.mjs';

/** A Cem Yuksel .hair file written from its specification: `n` strands of `pts` points (points only) rooted on
 * a sphere of radius `r` (file units) at azimuths from `a0` over `da` and elevations from `b0` over `db` (rad),
 * hanging down by `down` per point, `back` per point towards -y and a little away from the head. */
function hairFile(n, pts, a0, da, b0, db, r, back, down) {
  const buf = Buffer.alloc(128 + n * pts * 12);
  buf.write('HAIR', 0, 'ascii');
  buf.writeUInt32LE(n, 4); buf.writeUInt32LE(n * pts, 8); buf.writeUInt32LE(2, 12); buf.writeUInt32LE(pts - 1, 16);
  buf.writeFloatLE(1, 20); buf.writeFloatLE(0, 24);
  let o = 128;
  for (let i = 0; i < n; i++) {
    const a = a0 + da * (i / n), b = b0 + db * ((i * 7919) % n) / n; // azimuth, elevation (rad)
    const root = [r * Math.sin(a) * Math.cos(b), -r * Math.cos(a) * Math.cos(b), r * Math.sin(b)];
    for (let j = 0; j < pts; j++) {
      const out = 0.004 * j; // hangs down, a little away from the head
      buf.writeFloatLE(root[0] * (1 + out), o); buf.writeFloatLE(root[1] * (1 + out) - back * j, o + 4); buf.writeFloatLE(root[2] - down * j, o + 8);
      o += 12;
    }
  }
  return buf;
}

describe('the default scene (100k render strands)', () => {
  let server, browser;
  before(async () => { server = await startServer(); browser = await launchBrowser(); });
  after(async () => { await browser?.close(); if (server) console.log(await stopServer(server)); });

  test('the page loads, WebGL2 works and hair is drawn', async () => {
    const { page, logs } = await openViewer(browser, server.url);
    const s = await page.evaluate(() => ({ webgl2: window.coiffure.webgl2, strands: window.coiffure.strands, errors: window.coiffure.errors }));
    assert.equal(s.webgl2, true, 'WebGL2 context');
    assert.equal(s.strands, 100000, 'the default hairstyle has 100k render strands');
    assert.deepEqual(s.errors, []);
    await page.screenshot({ path: join(artifacts, 'default-scene.png'), timeout: 180_000 });
    // Pixel statistics: the hair must change a sizeable part of the frame (not a blank or head-only frame).
    const px = await page.evaluate(() => window.coiffureDebug.hairPixelStats());
    console.log('pixel statistics', px);
    assert.ok(px.hairFraction > 0.03, `hair covers ${px.hairFraction} of the frame`);
    assert.ok(px.nonBackground > px.hairFraction * 0.9, 'the frame is not blank');
    // Viewer frame time in software rendering (information for bench/RESULTS.md): the first frames after
    // this point, however slow SwiftShader is.
    await page.evaluate(() => { window.coiffure.frameTimes.length = 0; });
    await page.waitForFunction(() => window.coiffure.frameTimes.length >= 4, null, { timeout: 300_000, polling: 500 });
    const times = await page.evaluate(() => window.coiffure.frameTimes.slice(1));
    times.sort((a, b) => a - b);
    const median = times[Math.floor(times.length / 2)];
    writeFileSync(join(artifacts, 'frame-times-default.json'), JSON.stringify({ strands: 100000, frames: times.length, median_ms: median, times_ms: times }));
    console.log(`viewer frame time, default scene, software rendering: median ${median.toFixed(1)} ms over ${times.length} frames`);
    // The CPU's work for the hair is flat in the number of strands: one lit draw call drawing all 100k strands
    // and one per shadow pass, as for the look test's 3k.
    const calls = await page.evaluate(() => ({ calls: window.coiffure.hairDrawCalls, segments: window.coiffure.hairSegmentsPerCall, lines: window.coiffureDebug.view.lineCount }));
    console.log('hair draw calls', calls);
    assert.equal(calls.lines, 1, 'strands of one hair are below a pixel');
    assert.equal(calls.calls, 3, 'lit strands, shadow depth, shadow opacity');
    assert.ok(calls.segments % 100000 === 0 && calls.segments / 100000 >= 4, `the lit call draws ${calls.segments} segments (every segment of the 100k strands)`);
    assert.ok(!logs.some((l) => l.startsWith('pageerror')), logs.join('\n'));
  });
});

describe('a comb stroke through the hair (issue 12; 5k render strands standing for a 100k-hair head)', () => {
  // The server records the session (`--record`); after the stroke the record is replayed headless
  // (`coiffure replay`, bit for bit the same haptic steps) for the per-step figures a 60 Hz viewer cannot see.
  const record = join(artifacts, 'comb-stroke.rec');
  const replayDir = join(artifacts, 'comb-stroke-replay');
  const scale = ['--render-strands', '5000', '--hairs-per-render-strand', '20'];
  let server, browser, page;
  before(async () => {
    rmSync(record, { force: true });
    server = await startServer([...scale, '--record', record]);
    browser = await launchBrowser();
    ({ page } = await openViewer(browser, server.url, { view: 'back' }));
  });
  after(async () => { await browser?.close(); if (server) console.log(await stopServer(server)); });

  test('the stroke stays off the clamp, its force is continuous, and the strands come back', async () => {
    assert.equal(await page.evaluate(() => window.coiffure.youControl), true, 'the first viewer controls');
    await page.screenshot({ path: join(artifacts, 'comb-before.png') });
    await page.evaluate(() => { window.coiffure.peakForce = 0; window.coiffure.maxDisplacement = 0; });
    // Down the back of the head, through the hanging hair: the pointer 24 cm in 0.6 s (0.4 m/s; the viewer's
    // pseudo-haptics scale its motion down as the hair resists, so the comb goes about 10 cm in the hair at
    // issue 12's 0.1-0.2 m/s, asserted below), the moves from a timer in the page (`strokeWorld`: real pointer
    // moves wait for software rendering's 0.5-1.3 s frames, which made the stroke 11 cm at 1.5-2 mm/s over
    // 60-90 s before), a screenshot at its end with the comb still in the hair.
    const timing = await strokeWorld(page, [0.0, -0.1, 0.06], [0.0, -0.1, -0.18], 0.6, 100, {
      beforeRelease: () => page.screenshot({ path: join(artifacts, 'comb-during.png') }),
    });
    // Released, the comb leaves the hair (the lifted plane, 6 cm out); the strands then have more than 1.2 s.
    await page.waitForTimeout(2500);
    await page.screenshot({ path: join(artifacts, 'comb-after.png') });
    const seen = await page.evaluate(() => ({ peak: window.coiffure.peakForce, moved: window.coiffure.maxDisplacement }));
    await browser.close();
    browser = null;
    console.log(await stopServer(server));
    server = null;
    execFileSync(binary, ['replay', record, ...scale, '--out', replayDir], { stdio: 'inherit' });
    const s = JSON.parse(readFileSync(join(replayDir, 'summary.json'), 'utf8'));
    console.log('comb stroke: page', timing, 'viewer', seen, 'replay', s);
    writeFileSync(join(artifacts, 'comb-stroke-timing.json'), JSON.stringify({ page: timing, viewer: seen, replay: s }));
    // What the viewer saw, and every haptic step of the session (issue 12's acceptance).
    assert.ok(seen.peak > 1e-3 && seen.peak < 3.3, `peak force in the viewer ${seen.peak} N`);
    assert.ok(seen.moved > 1e-3, `largest strand displacement in the viewer ${seen.moved} m`);
    assert.equal(s.rejected_readings, 0);
    assert.equal(s.clamp_steps, 0, 'steps at the device clamp');
    assert.ok(s.in_hair_steps > 500, `steps with the comb in the hair: ${s.in_hair_steps}`);
    // The stroke the server felt is the hand's: the comb's mean speed in the hair within issue 12's 0.1-0.2 m/s.
    assert.ok(s.in_hair_speed_m_s >= 0.1 && s.in_hair_speed_m_s <= 0.2, `the comb's speed in the hair ${s.in_hair_speed_m_s} m/s (page: ${JSON.stringify(timing)})`);
    assert.ok(s.final_max_displacement_m <= 0.03, `displacement at the end ${s.final_max_displacement_m} m`);
    // Continuity over the stroke's steps (the comb moving in the hair): the comb also rests pressed in the hair
    // for the seconds its screenshot takes, where a still comb feels the hair's static push only (5-10 mN).
    assert.ok(s.stroke_steps > 500, `stroke steps (in the hair, moving): ${s.stroke_steps}`);
    assert.ok(s.stroke_force_share >= 0.6, `share of the stroke's steps above 5 mN ${s.stroke_force_share} (in-hair steps: ${s.in_hair_force_share})`);
    // Issue 12's bounds: at most 0.08 m during the stroke and 0.1 N per step. The largest steps were the comb
    // catching a wisp near its roots (a strand point 5 mm from the root, where it can hardly move): the proxy
    // slowed by 0.01-0.016 m/s in one step and the coupling's plain damper (10 N s/m) passed it to the hand
    // (0.122, 0.072 and 0.164 N in three runs, 2026-11-24/25). The damper now relaxes (the coupling's
    // `damper_time`, a standard linear solid) and a joint of two strand pieces is one contact, not two:
    // 0.042 N replaying the 0.164 N run's pointer path.
    assert.ok(s.stroke_max_displacement_m <= 0.08, `displacement during the stroke ${s.stroke_max_displacement_m} m`);
    assert.ok(s.max_force_change_n <= 0.1, `largest one-step change ${s.max_force_change_n} N`);
  });
});

describe('interaction (5k render strands for speed in software rendering)', () => {
  let server, browser, page;
  before(async () => {
    server = await startServer(['--render-strands', '5000']);
    browser = await launchBrowser();
    ({ page } = await openViewer(browser, server.url, { view: 'back' }));
  });
  after(async () => { await browser?.close(); if (server) console.log(await stopServer(server)); });

  test('a malformed or unknown WebSocket message is answered with an error and the connection stays up', async () => {
    const before = await page.evaluate(() => window.coiffure.framesReceived);
    await page.evaluate(() => window.coiffure.send(new Uint8Array([0x7f, 1]).buffer));
    await page.evaluate(() => window.coiffure.send(new Uint8Array([0x01, 1, 0, 0, 0]).buffer));
    await page.evaluate(() => window.coiffure.send(new Uint8Array([0x01]).buffer));
    await page.waitForFunction(() => window.coiffure.errors.length >= 3, null, { timeout: 10_000 });
    const errors = await page.evaluate(() => window.coiffure.errors);
    assert.equal(errors[0].code, 2, 'unknown type');
    assert.match(errors[0].message, /unknown message type 0x7f/);
    assert.equal(errors[1].code, 1, 'malformed POSE');
    assert.match(errors[1].message, /POSE needs a 32-byte payload/);
    assert.equal(errors[2].code, 1, 'too short');
    await page.waitForFunction((n) => window.coiffure.framesReceived > n + 5 && window.coiffure.connected, before, { timeout: 10_000 });
  });

  test('scissors shorten strands', async () => {
    await page.evaluate(() => document.querySelector('button[data-tool="2"]').click());
    await page.waitForFunction(() => window.coiffure.tool === 2);
    const before = await page.evaluate(() => ({ segments: window.coiffure.segmentsDrawn, kept: window.coiffure.keptMean, version: window.coiffure.keptVersion }));
    assert.ok(before.segments > 0, `segments drawn before the cut: ${before.segments}`);
    // Closing the blades (button down) cuts, and dragging them cuts again every 2 cm.
    await dragWorld(page, [0.05, -0.1, -0.06], [-0.05, -0.1, -0.06], 40, 40);
    // The server sends STRANDS: the viewer draws fewer segments, and the pieces fall as chains.
    await page.waitForFunction((b) => window.coiffure.segmentsDrawn < b.segments && window.coiffure.keptVersion > b.version, before, { timeout: 10_000 });
    await page.waitForFunction(() => window.coiffure.chainPoints > 0, null, { timeout: 10_000 });
    const after = await page.evaluate(() => ({ segments: window.coiffure.segmentsDrawn, kept: window.coiffure.keptMean, cutMin: window.coiffure.cutMin, chainPoints: window.coiffure.chainPoints }));
    console.log('scissors', { before, after });
    assert.ok(after.kept < before.kept, `mean kept points ${after.kept} < ${before.kept}`);
    assert.ok(after.cutMin < 1, `a strand is shorter: ${after.cutMin}`);
    await page.waitForTimeout(1500);
    await page.screenshot({ path: join(artifacts, 'after-scissors.png') });
  });

  test('the sprayer wets the hair and the dryer lowers the wetness', async () => {
    await page.evaluate(() => document.querySelector('button[data-tool="4"]').click());
    await page.waitForFunction(() => window.coiffure.tool === 4);
    await dragWorld(page, [0.0, -0.1, 0.02], [0.0, -0.1, -0.04], 40, 50);
    await page.waitForTimeout(300);
    const wet = await page.evaluate(() => window.coiffure.wetnessMean);
    assert.ok(wet > 0, `wetness after spraying ${wet}`);
    await page.screenshot({ path: join(artifacts, 'after-sprayer.png') });
    await page.evaluate(() => document.querySelector('button[data-tool="3"]').click());
    await page.waitForFunction(() => window.coiffure.tool === 3);
    await dragWorld(page, [0.0, -0.1, 0.02], [0.0, -0.1, -0.04], 40, 50);
    await page.waitForTimeout(300);
    const dried = await page.evaluate(() => window.coiffure.wetnessMean);
    console.log('wetness', { wet, dried });
    // The real dryer (first-order drying, k0 = 0.05 1/s in the jet's core) takes off a few per cent in 2 s.
    assert.ok(dried > 0, `the hair is not dried out at once: ${dried}`);
    assert.ok(dried < wet, `wetness after drying ${dried} < ${wet}`);
  });

  test('the dryer blows the hairstyle and it falls back; a head turn swings it and it settles (issue 14)', async () => {
    const motion = () => page.evaluate(() => window.coiffure.latticeMotion());
    // Dryer: selected and brought to the hair at the back of the head (the nozzle aims into the screen), blowing
    // for 2 s while it moves 1 cm down, then taken away.
    await page.evaluate(() => document.querySelector('button[data-tool="3"]').click());
    await page.waitForFunction(() => window.coiffure.tool === 3);
    await page.waitForTimeout(1500);
    const rest = await motion();
    await page.screenshot({ path: join(artifacts, 'dryer-before.png') });
    let during = 0;
    await dragWorld(page, [0.0, -0.11, 0.0], [0.0, -0.11, -0.01], 40, 50, async (k) => {
      if (k % 10 === 9) during = Math.max(during, await motion());
      if (k === 35) await screenshotDrawn(page, join(artifacts, 'dryer-during.png'));
    });
    await page.mouse.move(5, 5);
    await page.waitForTimeout(2300);
    const after = await motion();
    await page.screenshot({ path: join(artifacts, 'dryer-after.png') });
    console.log('dryer blast: lattice motion relative to the head (m)', { rest, during, after });
    assert.ok(during > rest + 0.005, `the jet moves the hairstyle: ${during} m (before ${rest} m)`);
    assert.ok(after < 0.5 * during, `it falls back: ${after} m after, ${during} m during`);
    // Head turn of 30 degrees (key H's drag sends the same HEAD message), then back. The swing's peak is tracked
    // on a 10 ms timer started before the HEAD message and kept 1.2 s after the head has turned: the swing decays
    // with a time constant of about 0.45 s, and in software rendering a frame (and so a rAF-polled wait) can take
    // longer than that, so a window opened only once the wait has seen the turned head read 7 mm of a swing that
    // peaks at centimetres (CI, 2026-11-27).
    await page.evaluate(() => {
      const w = window;
      w.swingPeak = 0;
      w.swingTimer = setInterval(() => { w.swingPeak = Math.max(w.swingPeak, w.coiffure.latticeMotion()); }, 10);
    });
    await page.evaluate(() => window.coiffure.setHead(0.5236, 0));
    await page.waitForFunction(() => Math.abs(window.coiffure.headQuaternion[2] - Math.sin(0.2618)) < 1e-3, null, { timeout: 10_000, polling: 10 });
    await page.screenshot({ path: join(artifacts, 'head-turn-during.png') });
    await page.waitForTimeout(1200);
    const swing = await page.evaluate(() => { clearInterval(window.swingTimer); return window.swingPeak; });
    await page.waitForTimeout(2000);
    const settled = await motion();
    await page.screenshot({ path: join(artifacts, 'head-turn-after.png') });
    console.log('head turn 30 deg: lattice motion relative to the head (m)', { swing, settled });
    assert.ok(swing > 0.01, `the hair swings: ${swing} m`);
    assert.ok(settled < 0.5 * swing, `it settles: ${settled} m after 2 s, ${swing} m swing`);
    await page.evaluate(() => window.coiffure.setHead(0, 0));
    await page.waitForFunction(() => Math.abs(window.coiffure.headQuaternion[2]) < 1e-6, null, { timeout: 10_000 });
    await page.waitForTimeout(1500);
  });

  test('the dryer blows on the crown from above and the hair falls back while it stays (issue 30)', async () => {
    // The dryer's tool point is where it aims; its nozzle is 15 cm behind, along the view (the viewer draws it
    // there). Seen from above, pressed on the crown for 2 s (blowing), then the button let go with the dryer
    // held where it is; screenshots while it blows and 2.3 s after it stops (web/test/artifacts).
    const motion = () => page.evaluate(() => window.coiffure.latticeMotion());
    await page.evaluate(() => document.querySelector('button[data-tool="3"]').click());
    await page.waitForFunction(() => window.coiffure.tool === 3);
    await page.evaluate(() => { const v = document.getElementById('view-select'); v.value = 'above'; v.dispatchEvent(new Event('change')); });
    await page.waitForTimeout(1500);
    const rest = await motion();
    const at = await page.evaluate(() => window.coiffureDebug.project(0.0, -0.02, 0.1));
    // The dryer is brought over the crown before it is switched on, as a hand would: pressed at once, it blew all
    // the way there from where the last test left it (behind the head), and on a loaded host the hair sometimes did
    // not move at all in the 2 s (the project's CI of e73d08e; reproduced here beside two busy loops). The viewer
    // draws nothing while the dryer blows (the session, its FRAMEs and the poses go on: a software-rendered frame
    // holds the page for seconds), and the 2 s count from the hair's first move after the press the page handled.
    // What the page knows (the tool the FRAMEs show and its target, the button, the control) is printed.
    const pageState = () => page.evaluate(() => { const c = window.coiffure; return { tool: c.tool, toolPosition: c.toolPosition, toolTarget: c.toolTarget, pressed: c.toolPressed, youControl: c.youControl, framesReceived: c.framesReceived, errors: c.errors.slice(-3) }; });
    await page.evaluate(() => window.coiffureDebug.holdFrames(true));
    try {
      // Over the crown: the tool proxy (FRAME) within 1 cm of where the mouse puts the device, in at most 10 s.
      await page.mouse.move(at[0], at[1]);
      const over = await page.waitForFunction(() => { const c = window.coiffure, p = c.toolPosition, q = c.toolTarget; return Math.hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]) < 0.01; }, null, { polling: 20, timeout: 10_000 }).then(() => true, () => false);
      assert.ok(over, `the dryer comes over the crown within 10 s: ${JSON.stringify(await pageState())}`);
      await page.mouse.down();
      await page.waitForFunction(() => window.coiffure.toolPressed, null, { polling: 10 });
      // The jet moves the hair within a few global steps of the press; up to 10 s are allowed for a loaded host.
      const t0 = Date.now();
      const moved = await page.waitForFunction((r) => window.coiffure.latticeMotion() > r + 0.003, rest, { polling: 20, timeout: 10_000 }).then(() => true, () => false);
      console.log('dryer from above: the jet moved the hairstyle', moved ? `${Date.now() - t0} ms after the press` : 'not within 10 s', await pageState());
      await page.waitForTimeout(2000);
      const during = await motion();
      // The hair drawn is carried by one law (engine::scene::carry_strand; carriedHair.ts on the GPU): roots held by
      // the head, every segment at its rest length, however far the lattice carries the rest.
      // The state of one frame (the lattice the jet deforms, the head pose) and 400 strands' carried vertices (the
      // 100 the lattice moves most among them), read back from the GPU in the same task, against the engine's
      // Scene::render_vertex on that state (POST /debug/carried): point by point within 1e-5 m (float32 on the
      // GPU; the chain of follow the leader sums its rounding over a strand's vertices).
      const carried = await page.evaluate(() => window.coiffureDebug.carriedHair(400));
      const state = carried.state;
      delete carried.state;
      const answer = await fetch(new URL('debug/carried', server.url), {
        method: 'POST', headers: { 'content-type': 'application/json' },
        body: JSON.stringify({ nodes: state.nodes, head_rotation: state.headRotation, head_translation: state.headTranslation, vertices: state.vertices }),
      });
      assert.equal(answer.status, 200, await answer.clone().text());
      const engine = (await answer.json()).positions;
      let engineGap = 0, worstVertex = -1;
      for (let k = 0; k < state.vertices.length; k++) {
        const d = Math.hypot(engine[3 * k] - state.positions[3 * k], engine[3 * k + 1] - state.positions[3 * k + 1], engine[3 * k + 2] - state.positions[3 * k + 2]);
        if (d > engineGap) { engineGap = d; worstVertex = state.vertices[k]; }
      }
      console.log('GPU carried hair vs the engine\'s render_vertex on the same lattice', { vertices: state.vertices.length, largestGap: engineGap, worstVertex });
      assert.ok(state.vertices.length >= 400 * 2, `vertices compared: ${state.vertices.length}`);
      assert.ok(engineGap < 1e-5, `the viewer's carried hair is the engine's: vertex ${worstVertex} ${engineGap} m apart`);
      await screenshotDrawn(page, join(artifacts, 'dryer-above-blowing.png'));
      await page.evaluate(() => window.coiffureDebug.releaseButton());
      await page.waitForTimeout(2300);
      const after = await motion();
      await screenshotDrawn(page, join(artifacts, 'dryer-above-2.3s-after.png'));
      await page.mouse.up();
      console.log('dryer from above: lattice motion relative to the head (m)', { rest, during, after });
      console.log('the carried hair read back from the GPU while the dryer blows', carried);
      assert.ok(carried.rootError < 1e-5, `roots on the head: ${carried.rootError} m from their rest roots`);
      assert.ok(carried.lengthError < 1e-3, `segments at their rest lengths: worst relative change ${carried.lengthError}`);
      assert.ok(carried.largestMove > 0.005, `the lattice carries the hair: largest vertex move ${carried.largestMove} m`);
      assert.ok(during > rest + 0.003, `the jet moves the hairstyle: ${during} m (before ${rest} m)`);
      assert.ok(after < during, `it falls back: ${after} m after, ${during} m during`);
    } finally {
      await page.evaluate(() => window.coiffureDebug.holdFrames(false));
    }
    await page.evaluate(() => { const v = document.getElementById('view-select'); v.value = 'back'; v.dispatchEvent(new Event('change')); });
  });

  test('loading a hairstyle file replaces the live hairstyle; a malformed one is answered with an error', async () => {
    // A Cem Yuksel .hair file: 2000 strands of 12 points hanging down from the back of the scalp.
    const n = 2000, pts = 12;
    const buf = hairFile(n, pts, -1.2, 2.4, 0.2, 0.6, 0.1, 0.002, 0.018);
    const errorsBefore = await page.evaluate(() => window.coiffure.errors.length);
    await page.fill('#fit-follow', '0'); // the file's strands only (issue 34's follow strands: the next tests)
    await page.setInputFiles('#load', { name: 'tress.hair', mimeType: 'application/octet-stream', buffer: buf });
    await page.waitForFunction((k) => window.coiffure.strands === k, n, { timeout: 60_000 });
    const frames = await page.evaluate(() => window.coiffure.framesReceived);
    await page.waitForFunction((f) => window.coiffure.framesReceived > f + 5, frames, { timeout: 30_000 });
    const errs = await page.evaluate((k) => window.coiffure.errors.slice(k), errorsBefore);
    assert.deepEqual(errs, [], 'no error after a good file');
    await page.screenshot({ path: join(artifacts, 'after-load.png') });
    // A truncated file: an error naming the byte offset, and the loaded hairstyle stays.
    await page.setInputFiles('#load', { name: 'broken.hair', mimeType: 'application/octet-stream', buffer: buf.subarray(0, 1000) });
    await page.waitForFunction((k) => window.coiffure.errors.length > k, errorsBefore, { timeout: 30_000 });
    const e = await page.evaluate(() => window.coiffure.errors.at(-1));
    console.log('load', { strands: n, error: e });
    assert.match(e.message, /cannot read the hair file/);
    assert.equal(await page.evaluate(() => window.coiffure.strands), n);
  });

  test('the TressFX mohawk (y up) is fitted onto the head when loaded', async () => {
    // AMD's TressFX sample hairstyle from ../shared/data (not in the repository): 2,228 strands, y up, metres.
    const file = join(repoDir, '..', 'shared', 'data', 'tressfx', 'Ratboy_mohawk.tfx');
    const buf = readFileSync(file);
    // Forget the previous load's FIT, so that the wait below sees this file's (CI once read the earlier file's +z).
    // The load took 19 s on a quiet CI machine and over 120 s on a loaded one: the wait polls on a timer (a
    // software-rendered frame takes seconds) for up to 5 minutes.
    await page.evaluate(() => { window.coiffure.fit = null; });
    await page.fill('#fit-follow', '0');
    await page.setInputFiles('#load', { name: 'Ratboy_mohawk.tfx', mimeType: 'application/octet-stream', buffer: buf });
    await page.waitForFunction(() => window.coiffure.strands === 2228 && window.coiffure.fit !== null, null, { timeout: 300_000, polling: 250 });
    const fit = await page.evaluate(() => window.coiffure.fit);
    const frames = await page.evaluate(() => window.coiffure.framesReceived);
    await page.waitForFunction((f) => window.coiffure.framesReceived > f + 5, frames, { timeout: 30_000 });
    await page.screenshot({ path: join(artifacts, 'mohawk-fitted.png') });
    writeFileSync(join(artifacts, 'mohawk-fit.json'), JSON.stringify(fit, null, 1));
    console.log('mohawk fit', fit);
    // The format's convention: y up, facing +z, metres.
    assert.equal(fit.up, '+y');
    assert.equal(fit.front, '+z');
    assert.equal(fit.metersPerUnit, 1);
    // Ratboy's roots run from the top of his (long) head down his neck and back: only the head part (437 of
    // 2,228 strands, 20 %) can be on a scalp. Its roots sit on ours (measured: 18.8 % of the strands rooted,
    // their roots median 0.5 mm, p95 7.6 mm from the scalp) at scale 0.8, the end of the fit's range of head
    // sizes (a head 1.25x ours); the mane on his back is loose (hanging behind the neck).
    // Asserted: about the head part's share is rooted (a rooted root is within 10 mm by definition; the Rust test
    // the_tressfx_mohawk_lands_on_the_scalp checks the head part's roots, chosen from the file, against 5 / 15 mm).
    assert.ok(fit.rooted > 0.15 && fit.rooted < 0.3, `fraction of strands rooted on the scalp ${fit.rooted}`);
    assert.ok(fit.rootedMedian < 0.005, `rooted roots to the scalp: median ${fit.rootedMedian} m`);
    assert.ok(fit.scale >= 0.8 - 1e-6 && fit.scale <= 1.0, `scale ${fit.scale}`);
  });

  test('a guide-only groom is drawn as a full head with follow strands (issue 34)', async () => {
    // Sintel's TressFX hair (Blender Institute, CC-BY; 228 guide strands; not in the repository: give its path in
    // COIFFURE_SINTEL_TFX, e.g. assets/sintel_lite_v2_1/GEO-sintel_hair_emit.001-sintel_hair.tfx of
    // github.com/Scthe/TressFX-OpenGL), else a guide-only groom written here: 228 strands of 16 points over the
    // back and top of the scalp, in centimetres. Loaded with the default follow strands (the load bar's field
    // empty: as many per strand as bring the head to the server's 5,000 render strands, 20 here), the viewer
    // draws the file's strands and 20 around each one rooted on the scalp.
    const sintel = process.env.COIFFURE_SINTEL_TFX;
    let buf, name;
    if (sintel) {
      buf = readFileSync(sintel);
      name = 'sintel.tfx';
    } else {
      buf = hairFile(228, 16, -2.4, 4.8, 0.15, 1.2, 10, 0.2, 1.6);
      name = 'guides.hair';
    }
    await page.evaluate(() => { window.coiffure.fit = null; });
    await page.fill('#fit-follow', '');
    await page.setInputFiles('#load', { name, mimeType: 'application/octet-stream', buffer: buf });
    await page.waitForFunction(() => window.coiffure.fit !== null && window.coiffure.strands > 228, null, { timeout: 300_000, polling: 250 });
    const fit = await page.evaluate(() => window.coiffure.fit);
    const strands = await page.evaluate(() => window.coiffure.strands);
    const frames = await page.evaluate(() => window.coiffure.framesReceived);
    await page.waitForFunction((f) => window.coiffure.framesReceived > f + 3, frames, { timeout: 60_000, polling: 250 });
    const shot = sintel ? 'sintel-follow-strands.png' : 'guide-groom-follow-strands.png';
    await page.screenshot({ path: join(artifacts, shot), timeout: 180_000 });
    const info = await page.evaluate(() => document.getElementById('fit-info')?.textContent ?? '');
    writeFileSync(join(artifacts, shot.replace('.png', '.json')), JSON.stringify({ file: sintel ?? name, strands, fit, status: info }, null, 1));
    console.log('guide-only groom with follow strands', { file: sintel ?? name, strands, rooted: fit.rooted, status: info });
    // 228 strands + 20 around each rooted one: the rooted share of the file decides the count.
    const rooted = Math.round((strands - 228) / 20);
    assert.equal(strands, 228 + 20 * rooted, `${strands} strands drawn`);
    assert.ok(rooted >= 0.5 * 228 * fit.rooted && rooted <= 228, `${rooted} strands with follow strands, ${fit.rooted} of the file rooted`);
    assert.match(info, /units cm \(0\.01 m\)/, 'the units named, not the f32 0.009999999776');
    await page.fill('#fit-follow', '');
  });

  test('a second viewer watches; it controls only after TAKE_CONTROL', async () => {
    // Two pages software-render in one browser: each frame takes seconds, so the waits poll on a timer (not on
    // animation frames) and the watcher need not draw before it speaks the protocol.
    const poll = { timeout: 60_000, polling: 100 };
    // Neither page needs to draw for this test: both hold their frames, so that each reads its socket promptly
    // (the first before the second opens: its frames would hold up the second's load for a minute or more).
    await page.evaluate(() => window.coiffureDebug.holdFrames(true));
    const { page: second } = await openViewer(browser, server.url, { drawn: 0 });
    await second.evaluate(() => window.coiffureDebug.holdFrames(true));
    await second.waitForFunction(() => window.coiffure.viewers === 2, null, poll);
    assert.equal(await second.evaluate(() => window.coiffure.youControl), false);
    await second.evaluate(() => window.coiffure.send(new Uint8Array([0x05, 1]).buffer)); // RESET from a watcher
    await second.waitForFunction(() => window.coiffure.errors.some((e) => e.code === 4) || !window.coiffure.connected, null, poll);
    assert.equal(await second.evaluate(() => window.coiffure.closeReason), null, 'the watcher stays connected');
    assert.ok(await second.evaluate(() => window.coiffure.errors.some((e) => e.code === 4)), 'a watcher\'s RESET is refused (ERROR 4)');
    await second.evaluate(() => document.getElementById('take').click());
    await second.waitForFunction(() => window.coiffure.youControl === true, null, poll);
    await page.waitForFunction(() => window.coiffure.youControl === false, null, poll);
    await second.close();
    await page.waitForFunction(() => window.coiffure.youControl === true, null, poll);
    await page.evaluate(() => window.coiffureDebug.holdFrames(false));
    assert.equal(await page.evaluate(() => window.coiffure.closeReason), null);
  });
});
