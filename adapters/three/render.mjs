#!/usr/bin/env node
// Renders a glTF scene's shadow term with three.js in headless Chromium and writes frames that
// `shadowlab compare` scores (scenes/FRAME-CONTRACT.md): vis.png (16-bit grey, 1 = lit), coverage.png
// (8-bit grey, 255 where three.js drew a surface) and renderer.json (what three.js used: the shadow
// camera's clip-from-world matrix, map size, biases, shadow type, its own frame time).
//
// Two modes, one renderer:
//   node adapters/three/render.mjs --request REQUEST.json [--chromium PATH]
//        the adapter protocol (adapters/README.md): every frame of the request, the browser started
//        and the scene loaded once; each frame's keys are adapter.json's;
//   node adapters/three/render.mjs SCENE.glb -o DIR [--map-size 512] [--bias 0] [--normal-bias 0]
//        [--type PCF] [--radius 1] [--blur-samples 8] [--fit bounds|tight|fixed] [--extent E]
//        [--side gltf|front|back|double] [--shadow-side default|front|back|double] [--repeat 3]
//        [--width W --height H] [--light NAME] [--timeout-s 120] [--chromium PATH]
//        one frame; the key options are the same keys (kKeys below, `--map-size` for map_size).
//
// It serves the page, three.js (this folder's node_modules, pinned by package-lock.json) and the
// scene on 127.0.0.1 only, starts Chromium on it (WebGL 2 through ANGLE on SwiftShader: no GPU is
// needed), hands the page one frame's keys at a time and takes the pixels back by POST. Exit 0
// written (a request: read and run, each frame written or given its error.txt), 2 bad arguments or
// input, 3 the renderer failed (Chromium missing, a page error, a time-out).
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import zlib from 'node:zlib';

const here = path.dirname(fileURLToPath(import.meta.url));
const kManifestPath = path.join(here, 'adapter.json');
const kMaxSceneBytes = 512 * 1024 * 1024;
const kMaxRequestBytes = 64 * 1024 * 1024;
const kMaxSide = 16384;
const kMaxPixels = 8192 * 8192;
const kMaxFrames = 10000;

class UsageError extends Error {}     // exit 2
class RendererError extends Error {}  // exit 3
class FrameError extends Error {}     // one frame's failure: its error.txt, the batch goes on

// ---- the keys three.js takes: the one table ------------------------------------------------------
// adapter.json's `keys` must be exactly these (checked at start-up), and each is also a single-frame
// option (`--` and the name with '-' for '_'). The page reads them by these names.
const kKeys = [
  { name: 'map_size', type: 'int', default: 512, min: 16, max: 16384, help: "shadow.mapSize, texels per side (three.js's default 512)" },
  { name: 'bias', type: 'number', default: 0, min: -1, max: 1, help: 'shadow.bias, depth units (usually small negative)' },
  { name: 'normal_bias', type: 'number', default: 0, min: 0, max: 1e6, help: 'shadow.normalBias, world units along the normal' },
  { name: 'type', type: 'enum', default: 'PCF', values: ['Basic', 'PCF', 'PCFSoft', 'VSM'], help: 'renderer.shadowMap.type (three.js r187 renders PCFSoft as PCF)' },
  { name: 'radius', type: 'number', default: 1, min: 0, max: 64, help: 'shadow.radius (PCF and VSM softness)' },
  { name: 'blur_samples', type: 'int', default: 8, min: 1, max: 64, help: 'shadow.blurSamples (VSM)' },
  { name: 'fit', type: 'enum', default: 'bounds', values: ['bounds', 'tight', 'fixed'], help: "directional shadow camera: around the scene's bounding sphere, tight around its box as the light sees it, or +-extent" },
  { name: 'extent', type: 'number', default: 5, min: 1e-6, max: 1e9, help: 'fit=fixed: the half-size of the shadow camera, world units' },
  { name: 'side', type: 'enum', default: 'gltf', values: ['gltf', 'front', 'back', 'double'], help: "every material's side (gltf: each glTF material's doubleSided, as GLTFLoader maps it)" },
  { name: 'shadow_side', type: 'enum', default: 'default', values: ['default', 'front', 'back', 'double'], help: "every material's shadowSide (default: three.js's own, the side opposite side)" },
  { name: 'repeat', type: 'int', default: 3, min: 1, max: 100, help: 'timed renders after a warm-up (frame_ms is their median)' },
];
const kKeyByName = new Map(kKeys.map((k) => [k.name, k]));
const optionName = (k) => '--' + k.name.replace(/_/g, '-');

// The single-frame mode's other options (the request gives these as its own fields).
const kOptions = [
  { name: 'width', type: 'int', default: 0, min: 1, max: kMaxSide, help: "image width (default: the camera's extras)" },
  { name: 'height', type: 'int', default: 0, min: 1, max: kMaxSide, help: "image height (default: the camera's extras)" },
  { name: 'light', type: 'string', default: '', help: 'the light to render (default: the first)' },
  { name: 'timeout_s', type: 'number', default: 120, min: 1, max: 3600, help: 'seconds before the render is given up (exit 3)' },
  { name: 'chromium', type: 'string', default: '', help: 'the browser (default: $CHROMIUM, else /usr/bin/chromium)' },
];

function expected(k) {
  if (k.type === 'enum') return `one of ${k.values.join(', ')}`;
  if (k.type === 'bool') return 'true or false';
  if (k.type === 'int') return `a whole number ${k.min}..${k.max}`;
  return `a number ${k.min}..${k.max}`;
}

// A key's value, typed (from the request's JSON) or as text (from the command line), checked
// against its table row: the value, or a message "got X; expected Y".
function acceptValue(k, value, fromText) {
  if (k.type === 'string') return typeof value === 'string' ? { value } : { error: `got ${shown(value)}; expected a string` };
  if (k.type === 'enum') {
    if (typeof value === 'string' && k.values.includes(value)) return { value };
    return { error: `got ${fromText ? `"${value}"` : shown(value)}; expected ${expected(k)}` };
  }
  if (k.type === 'bool') {
    if (fromText && (value === 'true' || value === 'false')) return { value: value === 'true' };
    if (!fromText && typeof value === 'boolean') return { value };
    return { error: `got ${fromText ? `"${value}"` : shown(value)}; expected true or false` };
  }
  let v = value;
  if (fromText) {
    v = Number(value);
    if (value.trim() === '' || !Number.isFinite(v)) return { error: `got "${value}"; expected ${expected(k)}` };
  } else if (typeof v !== 'number' || !Number.isFinite(v)) {
    return { error: `got ${shown(value)}; expected ${expected(k)}` };
  }
  const text = fromText ? value : shown(value);
  if (k.type === 'int' && !Number.isInteger(v)) return { error: `got ${text}; expected ${expected(k)}` };
  if (v < k.min || v > k.max) return { error: `got ${text}; expected ${k.min}..${k.max}` };
  return { value: v };
}

function shown(value) {
  const text = JSON.stringify(value);
  return text === undefined ? String(value) : text.length > 80 ? text.slice(0, 77) + '...' : text;
}

const defaultKeys = () => Object.fromEntries(kKeys.map((k) => [k.name, k.default]));

// adapter.json, the manifest shadowlab reads: its keys must be this table's, field for field.
function readManifest() {
  let m;
  try {
    m = JSON.parse(fs.readFileSync(kManifestPath, 'utf8'));
  } catch (e) {
    throw new RendererError(`${kManifestPath}: ${e.message}; the adapter's manifest is broken`);
  }
  const fields = ['name', 'type', 'default', 'min', 'max', 'values', 'help'];
  const row = (k) => JSON.stringify(Object.fromEntries(fields.filter((f) => k[f] !== undefined).map((f) => [f, k[f]])));
  const keys = Array.isArray(m && m.keys) ? m.keys : [];
  const problems = [];
  for (let i = 0; i < Math.max(keys.length, kKeys.length); i++) {
    if (i >= kKeys.length) problems.push(`/keys/${i}: ${row(keys[i])} is not in render.mjs's table`);
    else if (i >= keys.length || row(keys[i]) !== row(kKeys[i])) problems.push(`/keys/${i}: expected ${row(kKeys[i])}`);
  }
  if (m.shadowlab_adapter !== 1) problems.push('/shadowlab_adapter: expected 1');
  if (typeof m.name !== 'string' || !/^[a-z0-9_-]+$/.test(m.name)) problems.push('/name: expected the adapter\'s name');
  const t = m.timeout_s || {};
  if (!(t.start > 0) || !(t.per_frame > 0)) problems.push('/timeout_s: expected {start, per_frame} in seconds');
  if (problems.length) throw new RendererError(`${kManifestPath} and render.mjs's key table disagree: ${problems.join('; ')}`);
  return { name: m.name, startS: t.start, perFrameS: t.per_frame };
}

// ---- the single-frame command line ------------------------------------------------------------------
function usage() {
  const lines = ['usage: node adapters/three/render.mjs SCENE.glb -o DIR [options]',
    '       node adapters/three/render.mjs --request REQUEST.json [--chromium PATH]   (adapters/README.md)', 'options:'];
  for (const k of [...kKeys, ...kOptions]) {
    const range = k.values ? k.values.join('|') : k.min !== undefined ? `${k.min}..${k.max}` : k.type === 'bool' ? 'true|false' : 'text';
    const def = k.default === '' || (k.type === 'int' && k.default < k.min) ? 'none' : k.default;
    lines.push(`  ${optionName(k)} ${range}  ${k.help} (default ${def})`);
  }
  return lines.join('\n');
}

function parseArgs(argv) {
  const byOption = new Map([...kKeys, ...kOptions].map((k) => [optionName(k), k]));
  const keys = defaultKeys();
  const options = Object.fromEntries(kOptions.map((k) => [k.name, k.default]));
  let scene = '';
  let out = '';
  let request = '';
  const given = new Set();
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '-h' || a === '--help') {
      process.stdout.write(usage() + '\n');
      process.exit(0);
    }
    if (a === '-o' || a === '--out' || a === '--request') {
      if (i + 1 >= argv.length) throw new UsageError(`${a}: expected a ${a === '--request' ? 'file' : 'folder'}`);
      if (a === '--request') request = argv[++i];
      else out = argv[++i];
      continue;
    }
    if (a.startsWith('--')) {
      const k = byOption.get(a);
      if (!k) throw new UsageError(`${a}: unknown option; expected one of ${[...byOption.keys()].join(', ')}, --request`);
      if (given.has(a)) throw new UsageError(`${a}: given twice`);
      given.add(a);
      if (i + 1 >= argv.length) throw new UsageError(`${a}: expected a value`);
      const r = acceptValue(k, argv[++i], true);
      if (r.error) throw new UsageError(`${a}: ${r.error}`);
      if (kKeyByName.has(k.name)) keys[k.name] = r.value;
      else options[k.name] = r.value;
      continue;
    }
    if (scene) throw new UsageError(`${a}: one scene only (already ${scene})`);
    scene = a;
  }
  if (request) {
    const extra = [...given].filter((o) => o !== '--chromium');
    if (scene || out || extra.length) throw new UsageError(`--request: the request names the scene, the frames and their keys; got also ${[scene, out && '-o', ...extra].filter((x) => x).join(', ')}`);
    return { request, chromium: options.chromium };
  }
  if (!scene) throw new UsageError('no scene given; expected a .glb file (`shadowlab export SCENE -o scene.glb` writes one)');
  if (!out) throw new UsageError('-o DIR is required');
  if ((options.width === 0) !== (options.height === 0)) throw new UsageError('--width and --height go together');
  if (options.width * options.height > kMaxPixels) throw new UsageError(`--width x --height: ${options.width * options.height} pixels; expected at most ${kMaxPixels}`);
  return { scene, out, keys, options };
}

// ---- the request (untrusted JSON, adapters/README.md) -------------------------------------------
function readRequest(file) {
  const fail = (pointer, message) => {
    throw new UsageError(`${file}: ${pointer ? pointer + ': ' : ''}${message}`);
  };
  let stat;
  try {
    stat = fs.statSync(file);
  } catch {
    fail('', 'no such file; expected the request shadowlab writes (adapters/README.md)');
  }
  if (!stat.isFile()) fail('', 'not a regular file');
  if (stat.size > kMaxRequestBytes) fail('', `${stat.size} bytes; expected at most ${kMaxRequestBytes}`);
  let j;
  try {
    j = JSON.parse(fs.readFileSync(file, 'utf8'));
  } catch (e) {
    fail('', `not JSON: ${e.message}`);
  }
  const isObject = (v) => v !== null && typeof v === 'object' && !Array.isArray(v);
  const onlyFields = (obj, pointer, allowed) => {
    for (const f of Object.keys(obj)) if (!allowed.includes(f)) fail(`${pointer}/${f}`, `unknown field; expected ${allowed.join(', ')}`);
  };
  const need = (obj, pointer, field, what) => {
    if (!Object.hasOwn(obj, field)) fail(`${pointer}/${field}`, `missing; expected ${what}`);
    return obj[field];
  };
  if (!isObject(j)) fail('', `got ${shown(j)}; expected an object {shadowlab_adapter_request, scene, light, width, height, frames}`);
  onlyFields(j, '', ['shadowlab_adapter_request', 'scene', 'source_scene', 'light', 'width', 'height', 'frames']);
  if (need(j, '', 'shadowlab_adapter_request', 'the protocol version, 1') !== 1) fail('/shadowlab_adapter_request', `got ${shown(j.shadowlab_adapter_request)}; expected 1`);
  const base = path.dirname(path.resolve(file));
  const scene = need(j, '', 'scene', 'the .glb file to render');
  if (typeof scene !== 'string' || !scene.toLowerCase().endsWith('.glb')) fail('/scene', `got ${shown(scene)}; expected a .glb file's path`);
  const light = need(j, '', 'light', "the light's name");
  if (typeof light !== 'string') fail('/light', `got ${shown(light)}; expected the light's name, a string`);
  const size = {};
  for (const f of ['width', 'height']) {
    const v = need(j, '', f, `the image's ${f} in pixels`);
    if (!Number.isInteger(v) || v < 1 || v > kMaxSide) fail(`/${f}`, `got ${shown(v)}; expected a whole number 1..${kMaxSide}`);
    size[f] = v;
  }
  if (size.width * size.height > kMaxPixels) fail('/width', `${size.width} x ${size.height} = ${size.width * size.height} pixels; expected at most ${kMaxPixels}`);
  const frames = need(j, '', 'frames', 'an array of frames');
  if (!Array.isArray(frames) || frames.length < 1 || frames.length > kMaxFrames) fail('/frames', `got ${Array.isArray(frames) ? `${frames.length} frames` : shown(frames)}; expected an array of 1..${kMaxFrames} frames`);
  const ids = new Set();
  const outs = new Set();
  const checked = frames.map((f, i) => {
    const at = `/frames/${i}`;
    const ff = (message, sub = '') => fail(`${at}${sub} (frame ${i}${isObject(f) && typeof f.id === 'string' ? `, id "${f.id}"` : ''})`, message);
    if (!isObject(f)) ff(`got ${shown(f)}; expected an object {id, out, keys}`);
    for (const field of Object.keys(f)) if (!['id', 'config', 'out', 'keys'].includes(field)) ff('unknown field; expected id, config, out, keys', `/${field}`);
    for (const field of ['id', 'out', 'keys']) if (!Object.hasOwn(f, field)) ff(`missing; expected ${field === 'keys' ? 'an object of keys' : 'a string'}`, `/${field}`);
    if (typeof f.id !== 'string' || f.id.length === 0 || f.id.length > 200) ff(`got ${shown(f.id)}; expected a string of 1..200 characters`, '/id');
    if (ids.has(f.id)) ff(`"${f.id}" again; expected each id once`, '/id');
    ids.add(f.id);
    if (Object.hasOwn(f, 'config') && typeof f.config !== 'string') ff(`got ${shown(f.config)}; expected a string`, '/config');
    if (typeof f.out !== 'string' || f.out === '') ff(`got ${shown(f.out)}; expected a folder's path`, '/out');
    const out = path.resolve(base, f.out);
    let st = null;
    try {
      st = fs.statSync(out);
    } catch {
      // reported below
    }
    if (!st) ff(`${out}: no such folder; expected an existing folder for the frame`, '/out');
    if (!st.isDirectory()) ff(`${out}: not a folder`, '/out');
    if (outs.has(out)) ff(`${out} again; expected a folder of its own for each frame`, '/out');
    outs.add(out);
    if (!isObject(f.keys)) ff(`got ${shown(f.keys)}; expected an object of the manifest's keys`, '/keys');
    const keys = defaultKeys();
    for (const name of Object.keys(f.keys)) {
      const k = kKeyByName.get(name);
      if (!k) ff(`unknown key; expected one of ${kKeys.map((x) => x.name).join(', ')} (adapter.json)`, `/keys/${name}`);
      const r = acceptValue(k, f.keys[name], false);
      if (r.error) ff(r.error, `/keys/${name}`);
      keys[name] = r.value;
    }
    return { index: i, id: f.id, out, keys };
  });
  return { scene: path.resolve(base, scene), light, width: size.width, height: size.height, frames: checked };
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
function greyPng(width, height, codes, bits) {
  // `codes`: the page's PNG codes, a Uint16Array (16 bits) or Uint8Array (8 bits), row 0 at the top.
  const stride = 1 + width * (bits / 8);
  const raw = Buffer.alloc(height * stride);
  for (let y = 0; y < height; y++) {
    let o = y * stride;
    raw[o++] = 0;  // filter: none
    const end = (y + 1) * width;
    if (bits === 16) {
      for (let i = y * width; i < end; i++) {
        const code = codes[i];
        raw[o++] = code >>> 8;  // big-endian
        raw[o++] = code & 255;
      }
    } else {
      raw.set(codes.subarray(y * width, end), o);
    }
  }
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(width, 0);
  ihdr.writeUInt32BE(height, 4);
  ihdr[8] = bits;
  ihdr[9] = 0;  // grey
  // Level 1: the file is an exchange between two programs on one machine, read once; level 6
  // costs the adapter several times as long per frame (bench/three_adapter_overhead.py).
  return Buffer.concat([Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]), chunk('IHDR', ihdr),
    chunk('IDAT', zlib.deflateSync(raw, { level: 1 })), chunk('IEND', Buffer.alloc(0))]);
}

// ---- the scene file -------------------------------------------------------------------------------
function readScene(scenePath, where) {
  let stat;
  try {
    stat = fs.statSync(scenePath);
  } catch {
    throw new UsageError(`${where}${scenePath}: no such file; expected a .glb (shadowlab export SCENE -o scene.glb)`);
  }
  if (!stat.isFile()) throw new UsageError(`${where}${scenePath}: not a regular file; expected a .glb`);
  if (stat.size > kMaxSceneBytes) throw new UsageError(`${where}${scenePath}: ${stat.size} bytes; expected at most ${kMaxSceneBytes}`);
  const bytes = fs.readFileSync(scenePath);
  if (bytes.length < 12 || bytes.toString('ascii', 0, 4) !== 'glTF') throw new UsageError(`${where}${scenePath}: not a binary glTF (no "glTF" magic); expected a .glb`);
  return bytes;
}

function chromiumPath(given) {
  const p = given || process.env.CHROMIUM || '/usr/bin/chromium';
  if (!fs.existsSync(p)) throw new RendererError(`${p}: no such browser; expected Debian's chromium (scripts/install-deps.sh installs it) or --chromium PATH`);
  return p;
}

// ---- one browser session: the scene loaded once, then frame after frame --------------------------
// The page (page.mjs) fetches /setup.json (light, width, height), loads /scene.glb, then asks /next
// for one frame's keys at a time and POSTs /result (or /frame-error) for it, until /next says done.
// `onFrame(frame, result, error)` is called for each frame as it comes back, before the page is
// given the next one. Resolves when every frame was answered; throws RendererError when the browser
// or the page fails as a whole (`timeouts.start` seconds to load the scene, `timeouts.frame(i)` for
// frame i; `timeouts.what` names the limit in the message).
let activeCleanup = null;
let stopping = '';  // the signal this process was stopped by

async function renderFrames({ sceneBytes, setup, frames, chromium, timeouts, onFrame }) {
  const browser = chromiumPath(chromium);
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'shadowlab-three-'));
  const threeRoot = path.join(here, 'node_modules', 'three');
  const types = { '.js': 'text/javascript', '.mjs': 'text/javascript', '.html': 'text/html', '.json': 'application/json' };
  let child = null;
  let watchdog = null;
  let server = null;
  let timer = null;
  let next = 0;     // the next frame to hand out
  let current = -1; // the frame the page is rendering
  const frameName = (i) => `frame ${i} (id "${frames[i].id}")`;
  const cleanup = async () => {
    clearTimeout(timer);
    if (watchdog && watchdog.exitCode === null && watchdog.signalCode === null) watchdog.kill('SIGKILL');
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
  };
  activeCleanup = cleanup;
  try {
    await new Promise((resolve, reject) => {
      const arm = (seconds, message) => {
        clearTimeout(timer);
        timer = setTimeout(() => reject(new RendererError(`${message} after ${seconds} s${timeouts.what}`)), seconds * 1000);
      };
      server = http.createServer((req, res) => {
        const url = new URL(req.url, 'http://127.0.0.1');
        const send = (code, type, body) => {
          res.writeHead(code, { 'Content-Type': type, 'Cache-Control': 'no-store' });
          res.end(body);
        };
        if (req.method === 'POST') {
          const parts = [];
          req.on('data', (d) => parts.push(d));
          req.on('end', () => {
            const body = alignedBody(parts);
            if (url.pathname === '/error') {
              send(200, 'text/plain', 'ok');
              return reject(new RendererError(`three.js page: ${body.toString('utf8').slice(0, 2000)}`));
            }
            if (current < 0 || url.searchParams.get('index') !== String(current)) {
              send(400, 'text/plain', 'no such frame');
              return reject(new RendererError(`the page sent ${url.pathname} for frame ${url.searchParams.get('index')}; expected frame ${current}`));
            }
            const i = current;
            current = -1;
            clearTimeout(timer);
            let result = null;
            let error = null;
            if (url.pathname === '/result') {
              try {
                const d0 = performance.now();
                result = decode(body, setup);
                result.exchangeMs = performance.now() - d0;
              } catch (e) {
                if (!(e instanceof FrameError)) return reject(e);
                error = e;
              }
            } else {
              error = new FrameError(`three.js page: ${body.toString('utf8').slice(0, 2000)}`);
            }
            // The frame is written (or its error) before the page is given the next one.
            try {
              onFrame(frames[i], result, error);
            } catch (e) {
              send(500, 'text/plain', 'failed');
              return reject(e);
            }
            send(200, 'text/plain', 'ok');
          });
          return;
        }
        if (url.pathname === '/next') {
          if (current >= 0) return reject(new RendererError(`the page asked for a frame while ${frameName(current)} was not back`));
          if (next >= frames.length) {
            clearTimeout(timer);
            send(200, types['.json'], JSON.stringify({ done: true }));
            return resolve();
          }
          current = next++;
          arm(timeouts.frame(current), `${frameName(current)}: no result`);
          return send(200, types['.json'], JSON.stringify({ index: current, keys: frames[current].keys }));
        }
        if (url.pathname === '/' || url.pathname === '/page.html') return send(200, types['.html'], fs.readFileSync(path.join(here, 'page.html')));
        if (url.pathname === '/page.mjs') return send(200, types['.mjs'], fs.readFileSync(path.join(here, 'page.mjs')));
        if (url.pathname === '/scene.glb') return send(200, 'model/gltf-binary', sceneBytes);
        if (url.pathname === '/setup.json') return send(200, types['.json'], JSON.stringify(setup));
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
      server.on('error', (e) => reject(new RendererError(`the page's server: ${e.message}`)));
      server.listen(0, '127.0.0.1', () => {
        const url = `http://127.0.0.1:${server.address().port}/`;
        // Flags: headless WebGL 2 through ANGLE on SwiftShader; no first-run, sync or background
        // connections (the machine reaches nothing but itself); a fresh profile each time.
        child = spawn(browser, ['--headless=new', '--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
          '--disable-background-networking', '--disable-component-update', '--disable-sync', '--disable-quic',
          '--no-first-run', '--no-default-browser-check', '--disable-extensions', '--mute-audio',
          `--user-data-dir=${profile}`, url], { stdio: ['ignore', 'ignore', 'pipe'], detached: true });
        // Chromium's group is not ours, so a kill of this process's group (shadowlab's time-out) does
        // not reach it: a watchdog of its own group, holding a pipe from this process, kills it and
        // removes its profile when the pipe closes, that is when this process ends however it ends.
        if (child.pid) {
          watchdog = spawn('/bin/sh', ['-c', 'read x; kill -9 -"$1" 2>/dev/null; sleep 1; rm -rf -- "$2"', 'three-watchdog', String(child.pid), profile],
            { stdio: ['pipe', 'ignore', 'ignore'], detached: true });
          watchdog.on('error', () => {});
          watchdog.stdin.on('error', () => {});
        }
        let stderr = '';
        child.stderr.on('data', (d) => { stderr = (stderr + d.toString()).slice(-4000); });
        child.on('error', (e) => reject(new RendererError(`${browser}: ${e.message}`)));
        child.on('exit', (code, signal) => reject(new RendererError(`${browser} ended (${signal || 'exit ' + code}) before ${current >= 0 ? frameName(current) + ' came back' : 'the frames were done'}${stderr ? ': ' + stderr.trim().split('\n').slice(-3).join(' | ') : ''}`)));
        arm(timeouts.start, 'the page did not load the scene');
      });
    });
  } catch (e) {
    // The frame in flight when the browser failed is that frame's failure too.
    if (current >= 0 && !stopping) {
      const name = `${frameName(current)}: `;
      try {
        onFrame(frames[current], null, new FrameError(e.message.startsWith(name) ? e.message.slice(name.length) : e.message));
      } catch {
        // the whole run's error says it
      }
    }
    throw e;
  } finally {
    activeCleanup = null;
    await cleanup();
  }
}

// shadowlab's time-out, a ^C: the browser and its profile go with this process.
for (const signal of ['SIGTERM', 'SIGINT', 'SIGHUP']) {
  process.on(signal, async () => {
    if (stopping) return;
    stopping = signal;
    process.stderr.write(`three adapter: ${signal}: stopping the browser\n`);
    if (activeCleanup) await activeCleanup();
    process.exit(3);
  });
}

// The POST body, copied once into memory where its planes (after the 4-byte header length and the
// header) start aligned: decode then reads the 16-bit codes in place rather than copying them again.
function alignedBody(parts) {
  const total = parts.reduce((n, p) => n + p.length, 0);
  if (total < 4) return Buffer.concat(parts);
  const pad = (4 - ((4 + Buffer.concat(parts, 4).readUInt32LE(0)) % 4)) % 4;
  const store = Buffer.allocUnsafeSlow(total + pad);
  let o = pad;
  for (const p of parts) o += p.copy(store, o);
  return store.subarray(pad);
}

function decode(body, setup) {
  if (body.length < 4) throw new FrameError('the page sent a short result');
  const headerLength = body.readUInt32LE(0);
  let meta;
  try {
    meta = JSON.parse(body.toString('utf8', 4, 4 + headerLength));
  } catch (e) {
    throw new FrameError(`the page sent a result whose header is not JSON: ${e.message}`);
  }
  const n = meta.width * meta.height;
  const planes = body.subarray(4 + headerLength);  // the shadow term's 16-bit codes, then coverage's bytes
  if (planes.length !== n * 3) throw new FrameError(`the page sent ${planes.length} bytes of pixels; expected ${n * 3}`);
  if (setup.width && (meta.width !== setup.width || meta.height !== setup.height)) throw new FrameError(`the page rendered ${meta.width}x${meta.height}; expected ${setup.width}x${setup.height}`);
  // The page checked the values (0..1, finite) before it made them codes.
  const vis = planes.byteOffset % 2 === 0
    ? new Uint16Array(planes.buffer, planes.byteOffset, n)
    : new Uint16Array(planes.buffer.slice(planes.byteOffset, planes.byteOffset + 2 * n));
  const coverage = planes.subarray(2 * n, 3 * n);
  return { meta, vis, coverage };
}

// ---- writing a frame --------------------------------------------------------------------------------
// renderer.json (scenes/FRAME-CONTRACT.md): `settings` holds every key, by its manifest name after
// `prefix` ("" in a request's frame, where shadowlab names the row from the method; "three." in the
// single-frame mode, where `shadowlab compare` names the configuration from these settings).
function rendererJson(prefix, keys, meta) {
  const settings = {};
  for (const k of kKeys) settings[prefix + k.name] = keys[k.name];
  const renderer = {
    name: `three.js r${meta.three_revision} ${keys.type}`,
    light_clip_from_world: meta.light_clip_from_world,
    // What three.js used: it shrinks a map larger than the GPU's largest texture.
    map_size: meta.map_size,
    normal_bias_world: keys.normal_bias,
    depth_bias: keys.bias,
    filter: keys.type,
    frame_ms: meta.frame_ms,
    settings,
  };
  // A point light's cube faces are not declared: the key is left out rather than written empty.
  if (renderer.light_clip_from_world.length === 0) delete renderer.light_clip_from_world;
  return renderer;
}

// Written under a temporary name, then renamed: the file is there whole or not at all.
function writeAtomically(file, data) {
  const tmp = path.join(path.dirname(file), `.${path.basename(file)}.tmp-${process.pid}`);
  fs.writeFileSync(tmp, data);
  fs.renameSync(tmp, file);
}

// vis.png, coverage.png, then renderer.json (its presence says the frame is complete).
function writeFrame(dir, prefix, keys, { meta, vis, coverage }) {
  fs.writeFileSync(path.join(dir, 'vis.png'), greyPng(meta.width, meta.height, vis, 16));
  fs.writeFileSync(path.join(dir, 'coverage.png'), greyPng(meta.width, meta.height, coverage, 8));
  const renderer = rendererJson(prefix, keys, meta);
  writeAtomically(path.join(dir, 'renderer.json'), JSON.stringify(renderer, null, 2) + '\n');
  if (meta.map_size !== keys.map_size) process.stderr.write(`three adapter: note: map_size ${keys.map_size} is larger than this GPU's textures; three.js rendered ${meta.map_size}\n`);
  return renderer;
}

const describe = (renderer, meta) => `${renderer.name}: ${meta.width}x${meta.height}, light "${meta.light}", ` +
  `frame ${renderer.frame_ms === null ? '?' : renderer.frame_ms.toFixed(2)} ms (${meta.gl_renderer})`;

// ---- the two modes ----------------------------------------------------------------------------------
async function renderOne(parsed, manifest) {
  const { scene, out, keys, options } = parsed;
  if (fs.existsSync(out) && !fs.statSync(out).isDirectory()) throw new UsageError(`-o ${out}: exists and is not a folder`);
  const parent = path.dirname(path.resolve(out));
  if (!fs.existsSync(parent)) throw new UsageError(`-o ${out}: the folder ${parent} does not exist`);
  const sceneBytes = readScene(scene, '');
  const frame = { index: 0, id: '0', out, keys };
  let got = null;
  const started = Date.now();
  const left = () => Math.max(0.001, options.timeout_s - (Date.now() - started) / 1000);
  await renderFrames({
    sceneBytes, frames: [frame], chromium: options.chromium,
    setup: { light: options.light, width: options.width, height: options.height },
    timeouts: { start: options.timeout_s, frame: left, what: ' (--timeout-s)' },
    onFrame: (f, result, error) => { got = { result, error }; },
  });
  if (got.error) throw new RendererError(got.error.message);
  // Written into a new folder beside DIR, then renamed: DIR appears whole or not at all.
  const tmp = `${out}.tmp-${process.pid}`;
  fs.rmSync(tmp, { recursive: true, force: true });
  fs.mkdirSync(tmp, { recursive: true });
  const renderer = writeFrame(tmp, `${manifest.name}.`, keys, got.result);
  fs.rmSync(out, { recursive: true, force: true });
  fs.renameSync(tmp, out);
  process.stdout.write(`${describe(renderer, got.result.meta)}; wrote ${out}/vis.png, coverage.png, renderer.json\n`);
}

async function renderRequest(parsed, manifest) {
  const request = readRequest(parsed.request);
  const sceneBytes = readScene(request.scene, `${parsed.request}: /scene: `);
  const started = Date.now();
  let written = 0;
  let failed = 0;
  await renderFrames({
    sceneBytes, frames: request.frames, chromium: parsed.chromium,
    setup: { light: request.light, width: request.width, height: request.height },
    timeouts: { start: manifest.startS, frame: () => manifest.perFrameS, what: ` (${kManifestPath} timeout_s)` },
    onFrame: (frame, result, error) => {
      const name = `frame ${frame.index} (id "${frame.id}")`;
      if (result) {
        try {
          const w0 = performance.now();
          const renderer = writeFrame(frame.out, '', frame.keys, result);
          // The file exchange on this side: the pixels decoded from the page's POST, the PNGs
          // encoded and written (bench/RESULTS.md sets it against frame_ms).
          const exchange = result.exchangeMs + (performance.now() - w0);
          written++;
          process.stdout.write(`${name}: ${describe(renderer, result.meta)}; wrote ${frame.out} (exchange ${exchange.toFixed(2)} ms)\n`);
          return;
        } catch (e) {
          error = new FrameError(`could not write the frame: ${e.message}`);
        }
      }
      failed++;
      const line = error.message.replace(/\s+/g, ' ').trim();
      process.stderr.write(`three adapter: ${name}: error: ${line}\n`);
      try {
        writeAtomically(path.join(frame.out, 'error.txt'), line + '\n');
      } catch (e) {
        process.stderr.write(`three adapter: ${name}: could not write error.txt: ${e.message}\n`);
      }
    },
  });
  process.stdout.write(`three adapter: ${request.frames.length} frames (${written} written, ${failed} failed) in ${((Date.now() - started) / 1000).toFixed(2)} s\n`);
}

async function main() {
  try {
    const parsed = parseArgs(process.argv.slice(2));
    const manifest = readManifest();
    if (parsed.request) await renderRequest(parsed, manifest);
    else await renderOne(parsed, manifest);
    return 0;
  } catch (e) {
    const who = 'three adapter';
    if (e instanceof UsageError) {
      process.stderr.write(`${who}: error: ${e.message}\n`);
      return 2;
    }
    process.stderr.write(`${who}: error: ${e instanceof RendererError || e instanceof FrameError ? e.message : e.stack || e}\n`);
    return 3;
  }
}

process.exitCode = await main();
