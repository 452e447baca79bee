// Builds the viewer into dist/: bundles src/main.ts with esbuild and copies the static files.
import { build } from 'esbuild';
import { cpSync, mkdirSync } from 'node:fs';

mkdirSync('dist', { recursive: true });
await build({
  entryPoints: ['src/main.ts'],
  bundle: true,
  format: 'esm',
  target: 'es2022',
  minify: true,
  sourcemap: true,
  outfile: 'dist/main.js',
  logLevel: 'warning',
});
cpSync('index.html', 'dist/index.html');
cpSync('style.css', 'dist/style.css');
console.log('viewer built into web/dist');
