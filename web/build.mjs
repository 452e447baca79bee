// Builds the viewer into dist/: bundles src/main.ts with esbuild and copies the static files.
import { build } from 'esbuild';
import { cpSync, mkdirSync, rmSync } from 'node:fs';

// Source maps only on request (COIFFURE_SOURCEMAP=1): the server serves dist/ to anyone who may connect, and a
// 3 MB map of the sources is not part of the app.
const maps = process.env.COIFFURE_SOURCEMAP === '1';
mkdirSync('dist', { recursive: true });
if (!maps) rmSync('dist/main.js.map', { force: true });
await build({
  entryPoints: ['src/main.ts'],
  bundle: true,
  format: 'esm',
  target: 'es2022',
  minify: true,
  sourcemap: maps,
  outfile: 'dist/main.js',
  logLevel: 'warning',
});
cpSync('index.html', 'dist/index.html');
cpSync('style.css', 'dist/style.css');
console.log('viewer built into web/dist');
