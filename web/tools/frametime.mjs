// SwiftShader frame time of the viewer (information, not a test): renders the default view `frames` times
// with window.coiffureDebug.look (one synchronous render plus a readPixels) and prints the median.
// node tools/frametime.mjs [strands=100000] [width=1024] [height=720] [frames=5] ['{look options}'] (from web/).
import { launchBrowser, startServer, stopServer } from '../test/harness.mjs';

const [strands = '100000', width = '1024', height = '720', frames = '5', opts = '{}'] = process.argv.slice(2);
const server = await startServer(['--render-strands', strands]);
const browser = await launchBrowser();
try {
  const page = await browser.newPage({ viewport: { width: Number(width), height: Number(height) } });
  page.setDefaultTimeout(600_000);
  page.on('pageerror', (e) => console.log('pageerror:', e.message));
  await page.goto(server.url);
  await page.waitForFunction(() => window.coiffure?.sceneLoaded && window.coiffure.framesRendered > 1, null, { timeout: 300_000 });
  const ms = [];
  for (let i = 0; i < Number(frames); i++) {
    ms.push(await page.evaluate((o) => window.coiffureDebug.look(o).ms, JSON.parse(opts)));
  }
  const target = await page.evaluate(() => window.coiffureDebug.view.compositor?.target.texture.type ?? null);
  const sorted = [...ms].sort((a, b) => a - b);
  console.log(JSON.stringify({ strands: Number(strands), width: Number(width), height: Number(height), opts: JSON.parse(opts), hairTarget: target === null ? 'none (opaque lines)' : target === 1015 ? 'float32' : 'half float', ms: ms.map((x) => Math.round(x)), median_ms: Math.round(sorted[Math.floor(sorted.length / 2)]) }));
} finally {
  await browser.close();
  await stopServer(server);
}
