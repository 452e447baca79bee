// `coiffure serve --device`: a simulated haptic device (`coiffure device-sim`, UDP) drives the tool; the
// viewer shows the tool moving and the device's status (issue 13).
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { execFile } from 'node:child_process';
import { mkdirSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { artifacts, binary, launchBrowser, openViewer, repoDir, startServer, stopServer } from './harness.mjs';

describe('a haptic device drives the tool (5k render strands standing for a 100k-hair head)', () => {
  let server, browser;
  before(async () => {
    server = await startServer(['--device', 'udp:127.0.0.1:0', '--render-strands', '5000', '--hairs-per-render-strand', '20']);
    browser = await launchBrowser();
  });
  after(async () => { await browser?.close(); if (server) console.log(await stopServer(server)); });

  test('the device-driven comb moves in the viewer, which shows the device connected, then lost', async () => {
    const udp = server.output().match(/device on udp:([^ ]+)/)?.[1];
    assert.ok(udp, `the server printed its device address:\n${server.output()}`);
    const { page, logs } = await openViewer(browser, server.url);
    await page.waitForFunction(() => window.coiffure.device !== null, null, { timeout: 30_000 });
    assert.equal(await page.evaluate(() => window.coiffure.device.state), 'waiting');
    // The comb stroke of examples/scenarios/live-comb.toml slowed down for software rendering (a few frames a
    // second, fewer on a loaded machine): into the back hair in 1 s, drawn 11 cm down in 3 s, held there 6 s (so
    // that the busy page surely receives frames of the tool down there), out in 1 s.
    mkdirSync(artifacts, { recursive: true });
    const path = join(artifacts, 'device-comb.toml');
    const rot = '[0.0, 2.2214415, -2.2214415]';
    writeFileSync(path, `[live]\n[tool]\nshape = "comb"\npath = [\n  { t = 0.0, position = [0.0, -0.165, 0.03], rotation = ${rot} },\n  { t = 1.0, position = [0.0, -0.125, 0.03], rotation = ${rot} },\n  { t = 4.0, position = [0.0, -0.125, -0.08], rotation = ${rot} },\n  { t = 10.0, position = [0.0, -0.125, -0.08], rotation = ${rot} },\n  { t = 11.0, position = [0.0, -0.218, -0.08], rotation = ${rot} },\n]\n`);
    // Every FRAME's tool position as the page receives it (software rendering keeps the page busy for long
    // stretches, so the test does not poll): recorded by a setter on window.coiffure.toolPosition.
    await page.evaluate(() => {
      const s = window.coiffure;
      let v = s.toolPosition;
      window.toolSeen = [];
      Object.defineProperty(s, 'toolPosition', { configurable: true, get: () => v, set: (x) => { v = x; window.toolSeen.push([x[0], x[1], x[2], s.device?.state]); } });
    });
    const sim = new Promise((res, rej) => execFile(binary, ['device-sim', '--server', `udp:${udp}`, '--path', path, '--rate', '1000', '--duration', '11.5'],
      { cwd: repoDir }, (e, out, err) => (e ? rej(new Error(`${e.message}\n${err}`)) : res(out))));
    // Mid-stroke (the comb drawn down the back hair from 1 s to 4 s): the screenshot artifact.
    await new Promise((r) => setTimeout(r, 2500));
    await page.screenshot({ path: join(artifacts, 'device-comb.png'), timeout: 180_000 });
    const simOut = await sim;
    console.log(simOut);
    // The end of the stream: the page (busy with software rendering) may still be working through older
    // DEVICE messages, so wait for one that counts (nearly) every pose sent and says lost.
    const sent = Number(simOut.match(/(\d+) poses sent/)[1]);
    await page.waitForFunction((n) => window.coiffure.device?.state === 'lost' && window.coiffure.device.accepted >= n, 0.9 * sent, { timeout: 60_000 });
    const text = await page.evaluate(() => document.getElementById('device').textContent);
    const seen = await page.evaluate(() => window.toolSeen);
    const connected = seen.filter((s) => s[3] === 'connected');
    const zs = connected.map((s) => s[2]);
    const ys = connected.map((s) => s[1]);
    console.log(`device status ${text}; tool z from ${Math.max(...zs).toFixed(3)} to ${Math.min(...zs).toFixed(3)} m, y from ${Math.min(...ys).toFixed(3)} to ${Math.max(...ys).toFixed(3)} m over ${connected.length} frames`);
    assert.ok(connected.length > 5, 'the viewer saw the device connected');
    // The path goes from z = 0.03 down to z = -0.08 and back out to y = -0.218 (head frame = world here).
    assert.ok(Math.max(...zs) - Math.min(...zs) > 0.05, `the tool moved down with the device: z ${zs}`);
    assert.match(text, /device: lost/);
    assert.ok(!logs.some((l) => l.startsWith('pageerror')), logs.join('\n'));
  });
});
