// The tool proxy's health in the viewer (issue 16): the runaway guard's count (FRAME) is shown in the status
// bar and exposed as window.coiffure.runaways. The pointer's target is held at the head's centre; it is kept out
// of the body as the tool is (a pointer's depth is a guess), so the comb is pressed onto the scalp through the
// hair, whose push stretches the coupling by about a millimetre: with the server's guard at 0.5 mm
// (`--max-proxy-lag 0.0005`) that is a runaway again and again.
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { launchBrowser, openViewer, startServer, stopServer } from './harness.mjs';

describe('proxy health', () => {
  let server, browser, page;
  before(async () => {
    server = await startServer(['--render-strands', '2000', '--max-proxy-lag', '0.0005']);
    browser = await launchBrowser();
    ({ page } = await openViewer(browser, server.url));
  });
  after(async () => { await browser?.close(); if (server) console.log(await stopServer(server)); });

  test('runaways are counted, shown and exposed', async () => {
    await page.waitForFunction(() => window.coiffure.framesReceived > 2, null, { timeout: 60_000 });
    assert.equal(await page.evaluate(() => window.coiffure.runaways), 0, 'none before the tool is pushed in');
    assert.equal(await page.evaluate(() => document.getElementById('health').textContent), '');
    await page.evaluate(() => {
      // POSE at the head's centre, identity rotation, no buttons.
      const b = new DataView(new ArrayBuffer(34));
      b.setUint8(0, 0x01); b.setUint8(1, 1);
      [0, 0, 0, 0, 0, 0, 1].forEach((x, i) => b.setFloat32(2 + 4 * i, x, true));
      // The viewer sends its own pointer's POSE every animation frame; the test's pose is sent every 2 ms
      // until the count is read, so the device point stays at the head's centre.
      window.healthPose = setInterval(() => window.coiffure.send(b.buffer), 2);
    });
    await page.waitForFunction(() => window.coiffure.runaways > 0, null, { timeout: 60_000 });
    const n = await page.evaluate(() => window.coiffure.runaways);
    await page.waitForFunction(() => /^proxy resets: \d+$/.test(document.getElementById('health').textContent), null, { timeout: 10_000 });
    console.log('runaways shown', n, await page.evaluate(() => document.getElementById('health').textContent));
    await page.evaluate(() => clearInterval(window.healthPose));
  });
});
