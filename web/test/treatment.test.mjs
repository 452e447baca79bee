// The viewer's treatment selector (issue 29): choosing a surface treatment beside the hair type sends
// SET_TREATMENT, and the live session reports it back in its FRAMEs with the tool-hair friction it now uses.
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { launchBrowser, openViewer, startServer, stopServer } from './harness.mjs';

describe('the treatment selector (a small scene: 2k render strands)', () => {
  let server, browser;
  before(async () => { server = await startServer(['--render-strands', '2000']); browser = await launchBrowser(); });
  after(async () => { await browser?.close(); if (server) console.log(await stopServer(server)); });

  test('each treatment selected is the session\'s, with its friction: conditioned < virgin < bleached < bleached twice', async () => {
    const { page, logs } = await openViewer(browser, server.url);
    await page.waitForFunction(() => window.coiffure.treatment === 'virgin' && window.coiffure.toolFriction > 0, null, { timeout: 60_000 });
    const virgin = await page.evaluate(() => window.coiffure.toolFriction);
    const options = await page.evaluate(() => [...document.querySelectorAll('#treatment option')].map((o) => [o.value, o.textContent]));
    assert.deepEqual(options.map((o) => o[0]), ['0', '1', '2', '3'], 'one option per treatment, by wire id');
    const friction = { virgin };
    for (const [value, name] of [['1', 'conditioned'], ['2', 'bleached'], ['3', 'bleached-twice'], ['0', 'virgin']]) {
      await page.selectOption('#treatment', value);
      // The session's FRAMEs report the treatment it applied (not the viewer's own choice echoed).
      await page.waitForFunction((n) => window.coiffure.treatment === n, name, { timeout: 60_000 });
      friction[name] = await page.evaluate(() => window.coiffure.toolFriction);
      console.log(`treatment ${name}: tool friction ${friction[name]}`);
    }
    assert.ok(friction.conditioned < virgin && virgin < friction.bleached && friction.bleached < friction['bleached-twice'], JSON.stringify(friction));
    assert.equal(friction.virgin, virgin, 'back to virgin, back to its friction');
    assert.equal(await page.evaluate(() => document.getElementById('treatment').value), '0');
    assert.deepEqual(await page.evaluate(() => window.coiffure.errors), []);
    assert.ok(!logs.some((l) => l.startsWith('pageerror')), logs.join('\n'));
  });
});
