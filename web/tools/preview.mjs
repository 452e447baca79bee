// Renders preview images of the look into web/test-artifacts/preview, for docs/rendering.md and tuning:
// node tools/preview.mjs [strands] [width] [height] ['[{"name":..., "o": {look options}}]'] (from web/).
import { writeFileSync, mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { artifacts, launchBrowser, startServer, stopServer } from '../test/harness.mjs';

const strands = process.argv[2] ?? '20000';
const dir = join(artifacts, 'preview');
mkdirSync(dir, { recursive: true });
const server = await startServer(['--render-strands', strands]);
const browser = await launchBrowser();
try {
  const page = await browser.newPage({ viewport: { width: Number(process.argv[3] ?? 480), height: Number(process.argv[4] ?? 480) } });
  page.setDefaultTimeout(180_000);
  page.on('console', (m) => console.log('page:', m.text()));
  page.on('pageerror', (e) => console.log('pageerror:', e.message));
  await page.goto(server.url);
  await page.waitForFunction(() => window.coiffure?.sceneLoaded && window.coiffure.framesRendered > 2, null, { timeout: 120_000 });
  console.log(await page.evaluate(() => window.coiffureDebug.personInfo()));
  const shots = JSON.parse(process.argv[5] ?? '[]');
  const views = shots.length ? shots : [
    { name: 'back', o: {} },
    { name: 'front', o: { camera: [0.25, 0.75, 0.05], target: [0, 0, -0.05] } },
    { name: 'face', o: { camera: [0.12, 0.45, 0.0], target: [0, 0.05, -0.03], light: [0.4, 0.7, 0.6] } },
    { name: 'side', o: { camera: [0.7, 0.1, 0.05], target: [0, 0, -0.05], light: [0.6, 0.2, 0.7] } },
    { name: 'wet', o: { wetness: 1 } },
    { name: 'dom', o: { view: 1 } },
  ];
  for (const v of views) {
    const r = await page.evaluate((o) => window.coiffureDebug.look(o), v.o);
    writeFileSync(join(dir, `${v.name}.png`), Buffer.from(r.png.split(',')[1], 'base64'));
    console.log(v.name, r.ms.toFixed(0), 'ms');
  }
} finally {
  await browser.close();
  await stopServer(server);
}
