// The look (issue 17): screenshots of every hair colour preset, dry and wet, lit from two directions, and
// measurable image properties so the shading cannot silently break. Small canvas and 3k render strands to
// keep software rendering quick.
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { artifacts, launchBrowser, startServer, stopServer } from './harness.mjs';

const SIZE = 200;
const LIGHTS = { back: [0.7, -0.55, 0.3], side: [1.0, 0.15, 0.35] }; // back: the viewer's default
const COLOURS = ['blond', 'brown', 'black', 'red'];

/** Luminance (0..255) of RGBA pixel i. */
const lum = (px, i) => 0.2126 * px[4 * i] + 0.7152 * px[4 * i + 1] + 0.0722 * px[4 * i + 2];
const quantile = (xs, q) => { const s = Float64Array.from(xs).sort(); return s.length ? s[Math.min(s.length - 1, Math.floor(q * s.length))] : NaN; };
const mean = (xs) => xs.reduce((a, b) => a + b, 0) / Math.max(1, xs.length);

/** Mean width (m) of a fibre of elliptical section (major-axis diameter d, ellipticity e) about its axis:
 * perimeter / pi (Cauchy), the perimeter by Ramanujan's formula. */
const meanWidth = (d, e) => { const a = d / 2, b = d / (2 * e); return 3 * (a + b) - Math.sqrt((3 * a + b) * (a + 3 * b)); };

describe('the look (3k render strands, small canvas)', () => {
  let server, browser, page;
  const render = async (name, o) => {
    const r = await page.evaluate((opts) => window.coiffureDebug.look(opts), o);
    if (name) writeFileSync(join(artifacts, `${name}.png`), Buffer.from(r.png.split(',')[1], 'base64'));
    return { ...r, px: Buffer.from(r.pixels, 'base64') };
  };
  /** Indices of the pixels the hair changes against the same view without hair. */
  const hairMask = (img, bare) => {
    const m = [];
    for (let i = 0; i < img.px.length / 4; i++) {
      const d = Math.abs(img.px[4 * i] - bare.px[4 * i]) + Math.abs(img.px[4 * i + 1] - bare.px[4 * i + 1]) + Math.abs(img.px[4 * i + 2] - bare.px[4 * i + 2]);
      if (d > 12) m.push(i);
    }
    return m;
  };
  const camera = { camera: [0.3, -0.9, 0.22], target: [0, 0, -0.05] };
  const kept = {}; // images reused by later tests

  before(async () => {
    server = await startServer(['--render-strands', '3000']);
    browser = await launchBrowser();
    page = await browser.newPage({ viewport: { width: SIZE, height: SIZE } });
    page.setDefaultTimeout(180_000);
    await page.goto(server.url, { waitUntil: 'domcontentloaded' });
    await page.waitForFunction(() => window.coiffure?.sceneLoaded && window.coiffure.framesRendered > 1, null, { timeout: 120_000 });
  });
  after(async () => { await browser?.close(); if (server) console.log(await stopServer(server)); });

  test('the person: the sculpted face and ears stand out of the collision surface by at most 9 mm', async () => {
    const info = await page.evaluate(() => window.coiffureDebug.personInfo());
    console.log('person', info);
    // The refined body mesh lies on the metaball surface the hair collides with (Newton projection).
    assert.ok(info.maxProjectionError < 1e-5, `refined mesh off the surface by ${info.maxProjectionError} m`);
    // Nose tip and ears rise above it (there is a face), but by no more than PERSON_MAX_OUTSET.
    assert.ok(info.maxOutset > 0.004 && info.maxOutset <= 0.009, `largest outset ${info.maxOutset} m`);
    await render('look-face', { camera: [0.33, 0.45, 0.02], target: [0, 0.02, -0.04], light: [0.5, 0.6, 0.6], hideHair: true });
  });

  test('colour presets dry and wet, lit from two directions: melanin order, wet darker, highlight, shadows', async () => {
    const stats = {};
    const times = [];
    for (const [ln, light] of Object.entries(LIGHTS)) {
      const bare = await render(null, { ...camera, light, hideHair: true });
      if (ln === 'side') kept.bare = bare;
      for (const colour of COLOURS) {
        for (const wetness of [0, 1]) {
          const name = `look-${colour}-${wetness ? 'wet' : 'dry'}-${ln}`;
          const img = await render(name, { ...camera, light, colour, wetness });
          times.push(img.ms);
          if (name === 'look-brown-dry-side') kept.shaded = img;
          const mask = hairMask(img, bare);
          const l = mask.map((i) => lum(img.px, i));
          stats[name] = {
            hairPixels: mask.length, median: quantile(l, 0.5), p95: quantile(l, 0.95),
            redGreen: mean(mask.map((i) => img.px[4 * i])) / Math.max(1, mean(mask.map((i) => img.px[4 * i + 1]))),
          };
        }
      }
    }
    console.log('look statistics', stats);
    writeFileSync(join(artifacts, 'look-statistics.json'), JSON.stringify({ stats, renderMs: times }, null, 1));
    for (const ln of Object.keys(LIGHTS)) {
      const s = (c, w) => stats[`look-${c}-${w}-${ln}`];
      assert.ok(s('brown', 'dry').hairPixels > 0.05 * SIZE * SIZE, `hair covers ${s('brown', 'dry').hairPixels} pixels`);
      // Melanin: more eumelanin is darker.
      assert.ok(s('blond', 'dry').median > 1.3 * s('brown', 'dry').median, `${ln}: blond ${s('blond', 'dry').median} vs brown ${s('brown', 'dry').median}`);
      assert.ok(s('brown', 'dry').median > 1.2 * s('black', 'dry').median, `${ln}: brown ${s('brown', 'dry').median} vs black ${s('black', 'dry').median}`);
      // Pheomelanin: red hair is redder than brown and blond hair (mean red over mean green of the hair).
      for (const c of ['brown', 'blond']) {
        assert.ok(s('red', 'dry').redGreen > 1.08 * s(c, 'dry').redGreen, `${ln}: red R/G ${s('red', 'dry').redGreen} vs ${c} ${s(c, 'dry').redGreen}`);
      }
      // Wet hair is darker (longer absorbing paths under the water film).
      for (const c of COLOURS) {
        if (c === 'black') continue; // black is near the floor already
        assert.ok(s(c, 'wet').median < 0.85 * s(c, 'dry').median, `${ln} ${c}: wet ${s(c, 'wet').median} vs dry ${s(c, 'dry').median}`);
      }
    }
    // The two lights give different pictures.
    assert.notDeepEqual(stats['look-brown-dry-back'], stats['look-brown-dry-side']);
  });

  test('a highlight band brighter than the hair median, and darker hair where the deep opacity maps shadow it', async () => {
    const light = LIGHTS.side;
    const bare = kept.bare ?? await render(null, { ...camera, light, hideHair: true });
    const shaded = kept.shaded ?? await render(null, { ...camera, light, colour: 'brown' });
    const mask = hairMask(shaded, bare);
    const median = quantile(mask.map((i) => lum(shaded.px, i)), 0.5);
    // Highlight only (R lobe and water film under the direct light): its brightest tenth of the hair.
    const hl = await render('look-highlight-only', { ...camera, light, colour: 'brown', view: 2 });
    const hlL = mask.map((i) => lum(hl.px, i));
    const cut = quantile(hlL, 0.9);
    const band = mask.filter((i, k) => hlL[k] >= cut && hlL[k] > 8);
    const bandMean = mean(band.map((i) => lum(shaded.px, i)));
    console.log('highlight', { median, band: band.length, bandMean, cut });
    assert.ok(band.length > 0.02 * mask.length, `highlight pixels ${band.length} of ${mask.length}`);
    assert.ok(bandMean > 1.3 * median, `highlight band ${bandMean} vs hair median ${median}`);
    // Direct transmittance exp(-n) from the deep opacity maps: shadowed hair is darker than lit hair.
    const dom = await render('look-shadow-map', { ...camera, light, colour: 'brown', view: 1 });
    const t = (i) => dom.px[4 * i] / 255;
    const lit = mask.filter((i) => t(i) > 0.8), dark = mask.filter((i) => t(i) < 0.2);
    const litMean = mean(lit.map((i) => lum(shaded.px, i))), darkMean = mean(dark.map((i) => lum(shaded.px, i)));
    console.log('shadow', { lit: lit.length, dark: dark.length, litMean, darkMean });
    assert.ok(lit.length > 0.05 * mask.length && dark.length > 0.05 * mask.length, `lit ${lit.length}, shadowed ${dark.length} of ${mask.length}`);
    assert.ok(darkMean < 0.6 * litMean, `shadowed hair ${darkMean} vs lit ${litMean}`);
  });

  test('frame and GPU times are reported in window.coiffure and the status panel', async () => {
    await page.waitForFunction(() => window.coiffure.frameTimes.length > 3);
    const s = await page.evaluate(() => ({ gpuTimer: window.coiffure.gpuTimer, gpu: window.coiffure.gpuFrameMs, perf: document.getElementById('perf').textContent }));
    console.log('timing', s);
    assert.match(s.perf, /frame [0-9.]+ ms · GPU (n\/a|[0-9.]+ ms)/);
    if (s.gpuTimer) {
      await page.waitForFunction(() => window.coiffure.gpuFrameMs !== null, null, { timeout: 60_000 });
    } else {
      assert.equal(s.gpu, null, 'no timer query: no GPU time');
      assert.match(s.perf, /GPU n\/a/);
    }
  });

  // Last: it changes the server's hair type.
  test('strands are as wide as the fibres of the hair type the server sends in SCENE', async () => {
    const types = await page.evaluate(() => window.coiffure.hairTypes);
    const options = await page.evaluate(() => [...document.querySelectorAll('#preset option')].map((o) => o.textContent));
    console.log('hair types', types);
    assert.deepEqual(types.map((t) => t.name), options);
    for (const t of types) {
      assert.ok(t.diameter > 50e-6 && t.diameter < 150e-6, `${t.name}: diameter ${t.diameter} m`);
      assert.ok(t.ellipticity >= 1 && t.ellipticity < 3, `${t.name}: ellipticity ${t.ellipticity}`);
    }
    assert.ok(new Set(types.map((t) => t.diameter)).size >= 4, 'the presets have their own diameters');
    const width = () => page.evaluate(() => window.coiffure.strandWidth());
    const check = async (name) => {
      const t = types.find((x) => x.name === name);
      const w = await width();
      const want = meanWidth(t.diameter, t.ellipticity);
      assert.ok(Math.abs(w.fibreWidth / want - 1) < 1e-6, `${name}: fibre ${w.fibreWidth} m, want ${want} m`);
      assert.ok(Math.abs(w.width / (want * w.hairsPerStrand) - 1) < 1e-6 && w.hairsPerStrand > 1, `${name}: strand ${w.width} m`);
      return w.width;
    };
    const select = (name) => page.evaluate((i) => {
      const el = document.getElementById('preset');
      el.value = String(i);
      el.dispatchEvent(new Event('change'));
    }, types.findIndex((t) => t.name === name));
    const start = types[Number(await page.evaluate(() => document.getElementById('preset').value))].name;
    const other = start === 'asian' ? 'caucasian' : 'asian';
    const w0 = await check(start);
    await select(other);
    const w1 = await check(other);
    assert.notEqual(w0, w1);
    await select(start);
    await check(start);
  });
});
