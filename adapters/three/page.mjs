// Runs in headless Chromium (page.html): loads the scene's .glb with three.js's own GLTFLoader, keeps
// its camera and one light, replaces every material with a ShadowMaterial (the shadow term only), and
// renders into a float render target, so that what comes back is three.js's visibility, linear, with no
// tone mapping, sRGB encoding or premultiplication (those apply only to the canvas). The scene is
// loaded once; then render.mjs hands out one frame's keys at a time (GET /next) and each frame's
// pixels go back to it by POST before the next is asked for; nothing else leaves the page.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

const kShadowTypes = {
  Basic: THREE.BasicShadowMap,
  PCF: THREE.PCFShadowMap,
  PCFSoft: THREE.PCFSoftShadowMap,
  VSM: THREE.VSMShadowMap,
};
const kSides = { front: THREE.FrontSide, back: THREE.BackSide, double: THREE.DoubleSide };

function fail(message) {
  throw new Error(message);
}

// The first camera of the file (shadowlab's export writes one), at the pixel size the request names,
// else the one the camera node's extras name, else 640x480.
function setUpCamera(gltf, setup) {
  if (gltf.cameras.length === 0) fail('the glTF file has no camera; expected one (shadowlab export writes it)');
  const camera = gltf.cameras[0];
  // shadowlab export writes the size into the camera node's extras (shadowlab.camera.width/height).
  const node = camera.userData && camera.userData.shadowlab && camera.userData.shadowlab.camera;
  const size = node && Number.isInteger(node.width) && Number.isInteger(node.height) ? node : null;
  const width = setup.width || (size && size.width) || 640;
  const height = setup.height || (size && size.height) || 480;
  if (camera.isPerspectiveCamera) {
    camera.aspect = width / height;
  } else if (camera.isOrthographicCamera) {
    // glTF's ymag is half the view's height; the width follows the pixel aspect, as shadowlab's does.
    const halfHeight = (camera.top - camera.bottom) / 2;
    camera.left = -halfHeight * width / height;
    camera.right = halfHeight * width / height;
  }
  camera.updateProjectionMatrix();
  return { camera, width, height };
}

function findLight(scene, name) {
  const lights = [];
  scene.traverse((o) => {
    if (o.isDirectionalLight || o.isSpotLight || o.isPointLight) lights.push(o);
  });
  if (lights.length === 0) fail('the glTF file has no KHR_lights_punctual light; expected one to cast the shadows');
  if (!name) return { light: lights[0], others: lights.slice(1) };
  const light = lights.find((l) => l.name === name);
  if (!light) fail(`no light named "${name}"; the file has ${lights.map((l) => `"${l.name}"`).join(', ')}`);
  return { light, others: lights.filter((l) => l !== light) };
}

// An alpha-masked (glTF MASK) surface: a ShadowMaterial has no map, so the camera pass would draw its
// holes. A Lambert material keeps three.js's own alpha test (map alpha x opacity against alphaTest,
// as glTF defines it and shadowlab traces it) and writes the same output as a ShadowMaterial; the
// shadow pass copies map and alphaTest from it (WebGLShadowMap), so the holes cast no shadow.
function maskedShadowMaterial(original) {
  const material = new THREE.MeshLambertMaterial({ map: original.map, alphaTest: original.alphaTest, opacity: original.opacity });
  material.userData.shadowlabPatch = (shader) => {
    shader.fragmentShader = shader.fragmentShader
      .replace('#include <shadowmap_pars_fragment>', '#include <shadowmap_pars_fragment>\n#include <shadowmask_pars_fragment>')
      .replace('#include <opaque_fragment>', 'gl_FragColor = vec4( 1.0, 1.0, 1.0, 1.0 - getShadowMask() );');
  };
  return material;
}

// The frame contract's value for a spot light is 0 outside its cone, where three.js's shadow term is
// 1: every material multiplies its visibility by the cone test (the angle between the point's
// direction from the light and the light's axis at most the spot's angle, hard-edged as shadowlab's
// cone), written as 1 - alpha like the shadow term.
function patchMaterials(scene, light) {
  const spot = light.isSpotLight;
  const position = light.getWorldPosition(new THREE.Vector3());
  const axis = spot ? light.target.getWorldPosition(new THREE.Vector3()).sub(position).normalize() : null;
  scene.traverse((o) => {
    if (!o.isMesh) return;
    const own = o.material.userData.shadowlabPatch;
    o.material.onBeforeCompile = (shader) => {
      if (own) own(shader);
      if (!spot) return;
      shader.uniforms.slSpotPosition = { value: position };
      shader.uniforms.slSpotAxis = { value: axis };
      shader.uniforms.slSpotCos = { value: Math.cos(light.angle) };
      shader.vertexShader = 'varying vec3 slWorld;\n' + shader.vertexShader.replace('#include <worldpos_vertex>',
        '#include <worldpos_vertex>\nslWorld = ( modelMatrix * vec4( transformed, 1.0 ) ).xyz;');
      shader.fragmentShader = 'varying vec3 slWorld;\nuniform vec3 slSpotPosition;\nuniform vec3 slSpotAxis;\nuniform float slSpotCos;\n' +
        shader.fragmentShader.replace('1.0 - getShadowMask()',
          '1.0 - getShadowMask() * ( dot( normalize( slWorld - slSpotPosition ), slSpotAxis ) >= slSpotCos ? 1.0 : 0.0 )');
    };
    o.material.needsUpdate = true;
  });
}

// Every mesh gets a ShadowMaterial (opaque, so that its alpha, 1 - shadow, is written as it is; red 1
// marks coverage), made once; a frame's `side` and `shadow_side` are set on it by applyKeys. The glTF's
// own side (GLTFLoader maps doubleSided to DoubleSide, else FrontSide) is kept for side=gltf.
function replaceMaterials(scene) {
  const counts = { meshes: 0, alphaMasked: 0 };
  const materials = [];
  scene.traverse((o) => {
    if (!o.isMesh) return;
    const original = o.material;
    const masked = original.alphaTest > 0 && original.map;
    const material = masked ? maskedShadowMaterial(original) : new THREE.ShadowMaterial({ color: 0xffffff, opacity: 1 });
    material.transparent = false;
    material.userData.gltfSide = original.side;
    if (masked) counts.alphaMasked++;
    o.material = material;
    materials.push(material);
    const casts = !(o.userData && o.userData.shadowlab && o.userData.shadowlab.casts_shadow === false);
    o.castShadow = casts;
    o.receiveShadow = true;
    counts.meshes++;
  });
  return { counts, materials };
}

// The scene's box and bounding sphere, and for a directional light a light of our own at the scene's
// root, looking along the loaded one's direction at the sphere's centre from 2 radii away (the
// loaded light's node may sit anywhere: a glTF directional light has a direction only). Spot and
// point lights keep three.js's own perspective shadow cameras.
function placeLight(scene, light) {
  const box = new THREE.Box3();
  scene.traverse((o) => {
    if (o.isMesh) box.expandByObject(o);
  });
  const sphere = box.getBoundingSphere(new THREE.Sphere());
  const r = Math.max(sphere.radius, 1e-6);
  if (!light.isDirectionalLight) return { light, box, sphere, r };
  // GLTFLoader puts the light's target at (0, 0, -1) in the light node: the light looks down -Z.
  light.target.updateMatrixWorld(true);
  const from = light.getWorldPosition(new THREE.Vector3());
  const direction = light.target.getWorldPosition(new THREE.Vector3()).sub(from).normalize();
  light.parent.remove(light);
  const sun = new THREE.DirectionalLight(0xffffff, 1);
  sun.name = light.name;
  sun.position.copy(sphere.center).addScaledVector(direction, -2 * r);
  sun.target.position.copy(sphere.center);
  scene.add(sun);
  scene.add(sun.target);
  return { light: sun, box, sphere, r };
}

// The directional shadow camera's fit, per frame. "bounds" (the default, what most apps do by hand):
// an orthographic box of +-radius around the scene's bounding sphere, seen along the light, depth r..3r.
// "tight": the scene's axis-aligned box as the light sees it, its 8 corners in the light's view
// space giving min/max x, y and depth (padded by 1e-4 of the box's size, against rounding at its
// faces). "fixed": +-extent around the sphere's centre, depth as "bounds".
function fitShadowCamera(placed, keys) {
  const { light, box, r } = placed;
  if (!light.isDirectionalLight) return;
  const cam = light.shadow.camera;
  if (keys.fit === 'tight') {
    // The view three.js gives the shadow camera (LightShadow.updateMatrices): at the light, looking at
    // its target, up +Y.
    light.updateMatrixWorld(true);
    light.target.updateMatrixWorld(true);
    cam.position.setFromMatrixPosition(light.matrixWorld);
    cam.lookAt(new THREE.Vector3().setFromMatrixPosition(light.target.matrixWorld));
    cam.updateMatrixWorld(true);
    const lo = new THREE.Vector3(Infinity, Infinity, Infinity);
    const hi = new THREE.Vector3(-Infinity, -Infinity, -Infinity);
    const p = new THREE.Vector3();
    for (let i = 0; i < 8; i++) {
      p.set(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y, i & 4 ? box.max.z : box.min.z).applyMatrix4(cam.matrixWorldInverse);
      lo.min(p);
      hi.max(p);
    }
    const pad = 1e-4 * Math.max(hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 1e-6);
    cam.left = lo.x - pad;
    cam.right = hi.x + pad;
    cam.bottom = lo.y - pad;
    cam.top = hi.y + pad;
    // The camera looks down -Z: depth is -z.
    cam.near = -hi.z - pad;
    cam.far = -lo.z + pad;
  } else {
    const extent = keys.fit === 'fixed' ? keys.extent : r;
    cam.left = -extent;
    cam.right = extent;
    cam.top = extent;
    cam.bottom = -extent;
    cam.near = r;
    cam.far = 3 * r;
  }
  cam.updateProjectionMatrix();
}

// The shadow map three.js allocated for the last frame's size and type, freed (with VSM's blur
// target): the next render allocates one for this frame's.
function disposeShadowMap(shadow) {
  if (shadow.map) {
    if (shadow.map.depthTexture) {
      shadow.map.depthTexture.dispose();
      shadow.map.depthTexture = null;
    }
    shadow.map.dispose();
    shadow.map = null;
  }
  if (shadow.mapPass) {
    shadow.mapPass.dispose();
    shadow.mapPass = null;
  }
}

// One frame's keys (adapter.json's names) onto the stage, resetting whatever an earlier frame set.
function applyKeys(stage, keys) {
  const { renderer, light, materials } = stage;
  const last = stage.lastKeys;
  if (!last || last.map_size !== keys.map_size || last.type !== keys.type) disposeShadowMap(light.shadow);
  renderer.shadowMap.type = kShadowTypes[keys.type];
  light.shadow.mapSize.set(keys.map_size, keys.map_size);
  light.shadow.bias = keys.bias;
  light.shadow.normalBias = keys.normal_bias;
  light.shadow.radius = keys.radius;
  light.shadow.blurSamples = keys.blur_samples;
  for (const material of materials) {
    const side = keys.side === 'gltf' ? material.userData.gltfSide : kSides[keys.side];
    const shadowSide = keys.shadow_side === 'default' ? null : kSides[keys.shadow_side];
    if (material.side !== side || material.shadowSide !== shadowSide) {
      material.side = side;
      material.shadowSide = shadowSide;
      material.needsUpdate = true;
    }
  }
  fitShadowCamera(stage.placed, keys);
  stage.scene.updateMatrixWorld(true);
  stage.lastKeys = keys;
}

function unmaskedRenderer(gl) {
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  return info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
}

async function post(path, body) {
  const r = await fetch(path, { method: 'POST', body });
  if (!r.ok) throw new Error(`${path}: ${r.status} ${await r.text()}`);
}

// Everything a frame does not change, once: the scene, its camera, its light, the materials, the
// renderer and its float target.
async function loadStage() {
  const setup = await (await fetch('/setup.json')).json();
  const gltf = await new GLTFLoader().loadAsync('/scene.glb');
  const scene = gltf.scene;
  scene.updateMatrixWorld(true);
  const { camera, width, height } = setUpCamera(gltf, setup);
  const found = findLight(scene, setup.light);
  for (const other of found.others) other.parent.remove(other);
  const { counts, materials } = replaceMaterials(scene);
  const placed = placeLight(scene, found.light);
  const light = placed.light;
  scene.updateMatrixWorld(true);
  patchMaterials(scene, light);
  light.castShadow = true;

  const canvas = document.createElement('canvas');
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false });
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.shadowMap.enabled = true;
  const stage = { scene, camera, width, height, light, placed, materials, counts, renderer, lastKeys: null, shaderErrors: [] };
  // A program that does not link fails the frame that needed it (three.js would only log it).
  renderer.debug.onShaderError = (gl, program, vertexShader, fragmentShader) => {
    const log = [gl.getProgramInfoLog(program), gl.getShaderInfoLog(vertexShader), gl.getShaderInfoLog(fragmentShader)]
      .map((t) => (t || '').trim()).filter((t) => t).join(' | ');
    stage.shaderErrors.push(`a three.js shader program did not link: ${log.slice(0, 500)}`);
  };
  canvas.addEventListener('webglcontextlost', () => post('/error', 'the WebGL context was lost'));
  stage.gl = renderer.getContext();
  stage.target = new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType, depthBuffer: true });
  renderer.setRenderTarget(stage.target);
  renderer.setClearColor(0x000000, 0);
  return stage;
}

// One frame: its keys, a warm-up render (it compiles the programs and allocates the map), `repeat`
// timed renders (each is the frame's own work, the shadow pass and the camera pass, not the compile;
// a one-pixel read waits for it to be done: a finish alone need not, in a browser), the pixels.
function renderFrame(stage, keys) {
  const { scene, camera, width, height, light, renderer, target } = stage;
  applyKeys(stage, keys);
  stage.shaderErrors = [];
  const probe = new Float32Array(4);
  renderer.render(scene, camera);
  renderer.readRenderTargetPixels(target, 0, 0, 1, 1, probe);
  if (stage.shaderErrors.length) fail(stage.shaderErrors[0]);
  const times = [];
  for (let i = 0; i < keys.repeat; i++) {
    const t0 = performance.now();
    renderer.render(scene, camera);
    renderer.readRenderTargetPixels(target, 0, 0, 1, 1, probe);
    times.push(performance.now() - t0);
  }
  times.sort((a, b) => a - b);

  const rgba = new Float32Array(width * height * 4);
  renderer.readRenderTargetPixels(target, 0, 0, width, height, rgba);
  // WebGL's rows run bottom-up; the frame contract's row 0 is the top. Sent as the PNGs' codes (the
  // shadow term as 16 bits, coverage as 0 or 255): a third of the floats' bytes, nothing for the
  // adapter to convert. A value out of 0..1 (or NaN) fails the frame here, naming its pixel.
  const vis = new Uint16Array(width * height);
  const coverage = new Uint8Array(width * height);
  for (let y = 0; y < height; y++) {
    const src = (height - 1 - y) * width;
    for (let x = 0; x < width; x++) {
      const p = (src + x) * 4;
      const covered = rgba[p] > 0.5;
      const v = covered ? 1 - rgba[p + 3] : 0;
      if (!(v >= -1e-3 && v <= 1 + 1e-3)) throw new Error(`pixel (${x}, ${y}): visibility ${v}; expected 0..1`);
      coverage[y * width + x] = covered ? 255 : 0;
      vis[y * width + x] = Math.round((v < 0 ? 0 : v > 1 ? 1 : v) * 65535);
    }
  }
  const shadowCamera = light.shadow.camera;
  shadowCamera.updateMatrixWorld(true);
  const clipFromWorld = new THREE.Matrix4().multiplyMatrices(shadowCamera.projectionMatrix, shadowCamera.matrixWorldInverse);
  const meta = {
    width,
    height,
    light: light.name,
    light_type: light.isDirectionalLight ? 'directional' : light.isSpotLight ? 'spot' : 'point',
    // A point light's six cube faces are not declared (one layer per face would need their order).
    light_clip_from_world: light.isPointLight ? [] : [Array.from(clipFromWorld.elements)],
    // What three.js rendered: it shrinks a map larger than the GPU's largest texture.
    map_size: light.shadow.mapSize.x,
    frame_ms: times.length ? times[Math.floor(times.length / 2)] : null,
    frame_ms_all: times,
    meshes: stage.counts.meshes,
    alpha_masked: stage.counts.alphaMasked,
    three_revision: THREE.REVISION,
    gl_renderer: unmaskedRenderer(stage.gl),
  };
  // The header padded with spaces to a multiple of 4 bytes: the 16-bit codes then start aligned.
  let text = JSON.stringify(meta);
  while ((new TextEncoder().encode(text).length) % 4 !== 0) text += ' ';
  const header = new TextEncoder().encode(text);
  const length = new Uint32Array([header.length]);
  return new Blob([length, header, new Uint8Array(vis.buffer), coverage]);
}

async function main() {
  const stage = await loadStage();
  for (;;) {
    const job = await (await fetch('/next')).json();
    if (job.done) return;
    let body = null;
    try {
      body = renderFrame(stage, job.keys);
    } catch (e) {
      await post(`/frame-error?index=${job.index}`, String((e && e.message) || e));
      continue;
    }
    await post(`/result?index=${job.index}`, body);
  }
}

window.addEventListener('error', (e) => post('/error', String(e.message || e)));
window.addEventListener('unhandledrejection', (e) => post('/error', String((e.reason && e.reason.message) || e.reason)));
main().catch((e) => post('/error', String((e && e.message) || e)));
