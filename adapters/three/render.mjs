#!/usr/bin/env node
// Renders a glTF scene's shadow term with three.js in headless Chromium and writes a frame that
// `shadowlab compare` scores (scenes/FRAME-CONTRACT.md): vis.png (16-bit grey, 1 = lit), coverage.png
// (8-bit grey, 255 where three.js drew a surface) and renderer.json (what three.js used: the shadow
// camera's clip-from-world matrix, map size, biases, shadow type, its own frame time).
//
//   node adapters/three/render.mjs SCENE.glb -o DIR [--map-size 1024] [--bias 0] [--normal-bias 0]
//        [--type PCF] [--radius 1] [--blur-samples 8] [--fit bounds|fixed] [--extent E]
//        [--side front|back|double] [--shadow-side front|back|double] [--width W --height H]
//        [--light NAME] [--repeat 3] [--timeout-s 120] [--chromium PATH]
//
// It serves the page, three.js (this folder's node_modules, pinned by package-lock.json) and the
// scene on 127.0.0.1 only, starts Chromium on it (WebGL 2 through ANGLE on SwiftShader: no GPU is
// needed), and takes the pixels back by POST. Exit 0 written, 2 bad arguments or input, 3 the
// renderer failed (Chromium missing, a page error, a time-out); no output is left on failure.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import zlib from 'node:zlib';

const here = path.dirname(fileURLToPath(import.meta.url));
const kMaxSceneBytes = 512 * 1024 * 1024;
const kMaxPixels = 8192 * 8192;

class UsageError extends Error {}
class RendererError extends Error {}

// ---- arguments: the keys three.js takes, with their defaults and ranges ----------------------------
const kKeys = {
  'map-size': { key: 'mapSize', type: 'int', def: 1024, min: 16, max: 16384, help: 'shadow.mapSize, texels per side' },
  bias: { key: 'bias', type: 'float', def: 0, min: -1, max: 1, help: 'shadow.bias, depth units (usually small negative)' },
  'normal-bias': { key: 'normalBias', type: 'float', def: 0, min: 0, max: 1e6, help: 'shadow.normalBias, world units along the normal' },
  type: { key: 'type', type: 'enum', def: 'PCF', values: ['Basic', 'PCF', 'PCFSoft', 'VSM'], help: 'renderer.shadowMap.type' },
  radius: { key: 'radius', type: 'float', def: 1, min: 0, max: 64, help: 'shadow.radius (PCF and VSM softness)' },
  'blur-samples': { key: 'blurSamples', type: 'int', def: 8, min: 1, max: 64, help: 'shadow.blurSamples (VSM)' },
  fit: { key: 'fit', type: 'enum', def: 'bounds', values: ['bounds', 'fixed'], help: 'directional shadow camera: around the scene bounds, or +-extent' },
  extent: { key: 'extent', type: 'float', def: 5, min: 1e-6, max: 1e9, help: 'fit=fixed: the half-size of the shadow camera, world units' },
  side: { key: 'side', type: 'enum', def: '', values: ['', 'front', 'back', 'double'], help: "every material's side (default: each glTF material's doubleSided)" },
  'shadow-side': { key: 'shadowSide', type: 'enum', def: '', values: ['', 'front', 'back', 'double'], help: "every material's shadowSide (default: three.js's, the side opposite side)" },
  width: { key: 'width', type: 'int', def: 0, min: 1, max: 16384, help: "image width (default: the camera's extras)" },
  height: { key: 'height', type: 'int', def: 0, min: 1, max: 16384, help: "image height (default: the camera's extras)" },
  light: { key: 'light', type: 'string', def: '', help: 'the light to render (default: the first)' },
  repeat: { key: 'repeat', type: 'int', def: 3, min: 1, max: 100, help: 'timed renders after the warm-up (frame_ms is their median)' },
  'timeout-s': { key: 'timeoutS', type: 'float', def: 120, min: 1, max: 3600, help: 'seconds before the render is given up (exit 3)' },
  chromium: { key: 'chromium', type: 'string', def: '', help: 'the browser (default: $CHROMIUM, else /usr/bin/chromium)' },
};

function usage() {
  const lines = ['usage: node adapters/three/render.mjs SCENE.glb -o DIR [options]', 'options:'];
  for (const [name, k] of Object.entries(kKeys)) {
    const range = k.values ? k.values.filter((v) => v).join('|') : k.min !== undefined ? `${k.min}..${k.max}` : 'text';
    lines.push(`  --${name} ${range}  ${k.help} (default ${k.def === '' ? 'none' : k.def})`);
  }
  return lines.join('\n');
}

function parseArgs(argv) {
  const request = {};
  for (const k of Object.values(kKeys)) request[k.key] = k.def;
  let scene = '';
  let out = '';
  const given = new Set();
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '-h' || a === '--help') {
      process.stdout.write(usage() + '\n');
      process.exit(0);
    }
    if (a === '-o' || a === '--out') {
      if (i + 1 >= argv.length) throw new UsageError(`${a}: expected a folder`);
      out = argv[++i];
      continue;
    }
    if (a.startsWith('--')) {
      const name = a.slice(2);
      const k = kKeys[name];
      if (!k) throw new UsageError(`${a}: unknown option; expected one of ${Object.keys(kKeys).map((n) => '--' + n).join(', ')}`);
      if (given.has(name)) throw new UsageError(`${a}: given twice`);
      given.add(name);
      if (i + 1 >= argv.length) throw new UsageError(`${a}: expected a value`);
      const text = argv[++i];
      request[k.key] = parseValue(a, k, text);
      continue;
    }
    if (scene) throw new UsageError(`${a}: one scene only (already ${scene})`);
    scene = a;
  }
  if (!scene) throw new UsageError('no scene given; expected a .glb file (`shadowlab export SCENE -o scene.glb` writes one)');
  if (!out) throw new UsageError('-o DIR is required');
  if ((request.width === 0) !== (request.height === 0)) throw new UsageError('--width and --height go together');
  if (request.width * request.height > kMaxPixels) throw new UsageError(`--width x --height: ${request.width * request.height} pixels; expected at most ${kMaxPixels}`);
  return { scene, out, request };
}

function parseValue(option, k, text) {
  if (k.type === 'string') return text;
  if (k.type === 'enum') {
    if (!k.values.includes(text) || text === '') throw new UsageError(`${option}: got "${text}"; expected one of ${k.values.filter((v) => v).join(', ')}`);
    return text;
  }
  const v = Number(text);
  if (text.trim() === '' || !Number.isFinite(v)) throw new UsageError(`${option}: got "${text}"; expected a number ${k.min}..${k.max}`);
  if (k.type === 'int' && !Number.isInteger(v)) throw new UsageError(`${option}: got ${text}; expected a whole number ${k.min}..${k.max}`);
  if (v < k.min || v > k.max) throw new UsageError(`${option}: got ${text}; expected ${k.min}..${k.max}`);
  return v;
}

// ---- PNG (zlib is node's; the CRC is the PNG specification's) ---------------------------------------
const crcTable = (() => {
  const t = new Uint32Array(256);
  for (let n = 0; n < 256; n++) {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    t[n] = c >>> 0;
  }
  return t;
})();
function crc32(buf) {
  let c = 0xffffffff;
  for (let i = 0; i < buf.length; i++) c = crcTable[(c ^ buf[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}
function chunk(type, data) {
  const len = Buffer.alloc(4);
  len.writeUInt32BE(data.length);
  const td = Buffer.concat([Buffer.from(type, 'ascii'), data]);
  const crc = Buffer.alloc(4);
  crc.writeUInt32BE(crc32(td));
  return Buffer.concat([len, td, crc]);
}
// Grey PNG of `bits` 8 or 16 from values in [0, 1] (row 0 at the top): code = round(v * max).
function greyPng(width, height, values, bits) {
  const bytes = bits / 8;
  const max = bits === 16 ? 65535 : 255;
  const raw = Buffer.alloc(height * (1 + width * bytes));
  for (let y = 0; y < height; y++) {
    const row = y * (1 + width * bytes);
    raw[row] = 0;  // filter: none
    for (let x = 0; x < width; x++) {
      const v = values[y * width + x];
      const code = Math.round(Math.min(Math.max(v, 0), 1) * max);
      if (bits === 16) raw.writeUInt16BE(code, row + 1 + x * 2);
      else raw[row + 1 + x] = code;
    }
  }
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(width, 0);
  ihdr.writeUInt32BE(height, 4);
  ihdr[8] = bits;
  ihdr[9] = 0;  // grey
  return Buffer.concat([Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]), chunk('IHDR', ihdr),
    chunk('IDAT', zlib.deflateSync(raw, { level: 6 })), chunk('IEND', Buffer.alloc(0))]);
}

// ---- the page's server: 127.0.0.1 only, a fixed set of files ---------------------------------------
function serve(sceneBytes, request, onResult, onError) {
  const threeRoot = path.join(here, 'node_modules', 'three');
  const types = { '.js': 'text/javascript', '.mjs': 'text/javascript', '.html': 'text/html', '.json': 'application/json' };
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://127.0.0.1');
    const send = (code, type, body) => {
      res.writeHead(code, { 'Content-Type': type, 'Cache-Control': 'no-store' });
      res.end(body);
    };
    if (req.method === 'POST') {
      const parts = [];
      req.on('data', (d) => parts.push(d));
      req.on('end', () => {
        send(200, 'text/plain', 'ok');
        const body = Buffer.concat(parts);
        if (url.pathname === '/result') onResult(body);
        else onError(body.toString('utf8').slice(0, 2000));
      });
      return;
    }
    if (url.pathname === '/' || url.pathname === '/page.html') return send(200, types['.html'], fs.readFileSync(path.join(here, 'page.html')));
    if (url.pathname === '/page.mjs') return send(200, types['.mjs'], fs.readFileSync(path.join(here, 'page.mjs')));
    if (url.pathname === '/scene.glb') return send(200, 'model/gltf-binary', sceneBytes);
    if (url.pathname === '/request.json') return send(200, types['.json'], JSON.stringify(request));
    if (url.pathname.startsWith('/three/')) {
      // Only three's own build and examples, never a path outside them.
      const rel = path.normalize(decodeURIComponent(url.pathname.slice('/three/'.length)));
      const file = path.join(threeRoot, rel);
      const inside = (dir) => file.startsWith(path.join(threeRoot, dir) + path.sep);
      if ((inside('build') || inside('examples')) && fs.existsSync(file) && fs.statSync(file).isFile())
        return send(200, types[path.extname(file)] || 'application/octet-stream', fs.readFileSync(file));
    }
    send(404, 'text/plain', 'not found');
  });
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve(server)));
}

function chromiumPath(request) {
  const p = request.chromium || process.env.CHROMIUM || '/usr/bin/chromium';
  if (!fs.existsSync(p)) throw new RendererError(`${p}: no such browser; expected Debian's chromium (scripts/install-deps.sh installs it) or --chromium PATH`);
  return p;
}

async function render(scenePath, outDir, request) {
  let stat;
  try {
    stat = fs.statSync(scenePath);
  } catch {
    throw new UsageError(`${scenePath}: no such file; expected a .glb (shadowlab export SCENE -o scene.glb)`);
  }
  if (!stat.isFile()) throw new UsageError(`${scenePath}: not a regular file; expected a .glb`);
  if (stat.size > kMaxSceneBytes) throw new UsageError(`${scenePath}: ${stat.size} bytes; expected at most ${kMaxSceneBytes}`);
  const sceneBytes = fs.readFileSync(scenePath);
  if (sceneBytes.length < 12 || sceneBytes.toString('ascii', 0, 4) !== 'glTF') throw new UsageError(`${scenePath}: not a binary glTF (no "glTF" magic); expected a .glb`);
  const browser = chromiumPath(request);
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'shadowlab-three-'));
  let child = null;
  let server = null;
  let timer = null;
  try {
    const result = await new Promise(async (resolve, reject) => {
      server = await serve(sceneBytes, request, resolve, (msg) => reject(new RendererError(`three.js page: ${msg}`)));
      const url = `http://127.0.0.1:${server.address().port}/`;
      // Flags: headless WebGL 2 through ANGLE on SwiftShader; no first-run, sync or background
      // connections (the machine reaches nothing but itself); a fresh profile each time.
      child = spawn(browser, ['--headless=new', '--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
        '--disable-background-networking', '--disable-component-update', '--disable-sync', '--disable-quic',
        '--no-first-run', '--no-default-browser-check', '--disable-extensions', '--mute-audio',
        `--user-data-dir=${profile}`, url], { stdio: ['ignore', 'ignore', 'pipe'], detached: true });
      let stderr = '';
      child.stderr.on('data', (d) => { stderr = (stderr + d.toString()).slice(-4000); });
      child.on('error', (e) => reject(new RendererError(`${browser}: ${e.message}`)));
      child.on('exit', (code, signal) => reject(new RendererError(`${browser} ended (${signal || 'exit ' + code}) before the frame came back${stderr ? ': ' + stderr.trim().split('\n').slice(-3).join(' | ') : ''}`)));
      timer = setTimeout(() => reject(new RendererError(`no frame after ${request.timeoutS} s (--timeout-s)`)), request.timeoutS * 1000);
    });
    return decode(result);
  } finally {
    clearTimeout(timer);
    // Chromium runs in a process group of its own (detached): the whole group goes, its GPU and
    // renderer processes too, and the profile only once the browser is gone (it writes there).
    if (child && child.exitCode === null && child.signalCode === null) {
      const ended = new Promise((resolve) => child.once('exit', resolve));
      try {
        process.kill(-child.pid, 'SIGKILL');
      } catch {
        child.kill('SIGKILL');
      }
      await ended;
    }
    if (server) server.close();
    try {
      fs.rmSync(profile, { recursive: true, force: true, maxRetries: 10, retryDelay: 100 });
    } catch (e) {
      process.stderr.write(`three adapter: note: could not remove the browser profile ${profile}: ${e.message}\n`);
    }
  }
}

function decode(body) {
  if (body.length < 4) throw new RendererError('the page sent a short result');
  const headerLength = body.readUInt32LE(0);
  const meta = JSON.parse(body.toString('utf8', 4, 4 + headerLength));
  const n = meta.width * meta.height;
  const planes = body.subarray(4 + headerLength);  // vis then coverage, float32 each
  if (planes.length !== n * 8) throw new RendererError(`the page sent ${planes.length} bytes of pixels; expected ${n * 8}`);
  const copy = new Float32Array(planes.buffer.slice(planes.byteOffset, planes.byteOffset + planes.length));
  const vis = copy.subarray(0, n);
  const coverage = copy.subarray(n, 2 * n);
  for (let i = 0; i < n; i++) {
    if (!Number.isFinite(vis[i]) || vis[i] < -1e-3 || vis[i] > 1 + 1e-3) {
      throw new RendererError(`pixel (${i % meta.width}, ${Math.floor(i / meta.width)}): visibility ${vis[i]}; expected 0..1`);
    }
  }
  return { meta, vis, coverage };
}

// Written into a new folder beside DIR, then renamed: DIR appears whole or not at all.
function writeOutputs(outDir, request, { meta, vis, coverage }) {
  const tmp = `${outDir}.tmp-${process.pid}`;
  fs.rmSync(tmp, { recursive: true, force: true });
  fs.mkdirSync(tmp, { recursive: true });
  fs.writeFileSync(path.join(tmp, 'vis.png'), greyPng(meta.width, meta.height, vis, 16));
  fs.writeFileSync(path.join(tmp, 'coverage.png'), greyPng(meta.width, meta.height, coverage, 8));
  const settings = {
    'three.map_size': request.mapSize, 'three.bias': request.bias, 'three.normal_bias': request.normalBias,
    'three.type': request.type, 'three.radius': request.radius, 'three.blur_samples': request.blurSamples,
    'three.fit': request.fit,
  };
  if (request.fit === 'fixed') settings['three.extent'] = request.extent;
  if (request.side) settings['three.side'] = request.side;
  if (request.shadowSide) settings['three.shadow_side'] = request.shadowSide;
  const renderer = {
    name: `three.js r${meta.three_revision} ${request.type}`,
    light_clip_from_world: meta.light_clip_from_world,
    map_size: request.mapSize,
    normal_bias_world: request.normalBias,
    depth_bias: request.bias,
    filter: request.type,
    frame_ms: meta.frame_ms,
    settings,
  };
  // A point light's cube faces are not declared: the key is left out rather than written empty.
  if (renderer.light_clip_from_world.length === 0) delete renderer.light_clip_from_world;
  fs.writeFileSync(path.join(tmp, 'renderer.json'), JSON.stringify(renderer, null, 2) + '\n');
  fs.rmSync(outDir, { recursive: true, force: true });
  fs.renameSync(tmp, outDir);
  return renderer;
}

async function main() {
  let parsed;
  try {
    parsed = parseArgs(process.argv.slice(2));
    if (fs.existsSync(parsed.out) && !fs.statSync(parsed.out).isDirectory()) throw new UsageError(`-o ${parsed.out}: exists and is not a folder`);
    const parent = path.dirname(path.resolve(parsed.out));
    if (!fs.existsSync(parent)) throw new UsageError(`-o ${parsed.out}: the folder ${parent} does not exist`);
    const result = await render(parsed.scene, parsed.out, parsed.request);
    const renderer = writeOutputs(parsed.out, parsed.request, result);
    process.stdout.write(`${renderer.name}: ${result.meta.width}x${result.meta.height}, light "${result.meta.light}", ` +
      `frame ${renderer.frame_ms === null ? '?' : renderer.frame_ms.toFixed(2)} ms (${result.meta.gl_renderer}); wrote ${parsed.out}/vis.png, coverage.png, renderer.json\n`);
    return 0;
  } catch (e) {
    const who = 'three adapter';
    if (e instanceof UsageError) {
      process.stderr.write(`${who}: error: ${e.message}\n`);
      return 2;
    }
    process.stderr.write(`${who}: error: ${e instanceof RendererError ? e.message : e.stack || e}\n`);
    return 3;
  }
}

process.exitCode = await main();
