// Runs in headless Chromium (page.html): loads the scene's .glb with three.js's own GLTFLoader, keeps
// its camera and one light, replaces every material with a ShadowMaterial (the shadow term only), and
// renders into a float render target, so that what comes back is three.js's visibility, linear, with no
// tone mapping, sRGB encoding or premultiplication (those apply only to the canvas). The pixels go back
// to render.mjs by POST; nothing else leaves the page.
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
function setUpCamera(gltf, request) {
  if (gltf.cameras.length === 0) fail('the glTF file has no camera; expected one (shadowlab export writes it)');
  const camera = gltf.cameras[0];
  // shadowlab export writes the size into the camera node's extras (shadowlab.camera.width/height).
  const node = camera.userData && camera.userData.shadowlab && camera.userData.shadowlab.camera;
  const size = node && Number.isInteger(node.width) && Number.isInteger(node.height) ? node : null;
  const width = request.width || (size && size.width) || 640;
  const height = request.height || (size && size.height) || 480;
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

// Every mesh gets a ShadowMaterial of the same side (GLTFLoader maps doubleSided to DoubleSide, else
// FrontSide), opaque so that its alpha (1 - shadow) is written as it is; red 1 marks coverage.
function replaceMaterials(scene, request) {
  const counts = { meshes: 0, alphaMasked: 0 };
  scene.traverse((o) => {
    if (!o.isMesh) return;
    const original = o.material;
    const masked = original.alphaTest > 0 && original.map;
    const material = masked ? maskedShadowMaterial(original) : new THREE.ShadowMaterial({ color: 0xffffff, opacity: 1 });
    material.transparent = false;
    material.side = request.side ? kSides[request.side] : original.side;
    if (request.shadowSide) material.shadowSide = kSides[request.shadowSide];
    if (masked) counts.alphaMasked++;
    o.material = material;
    const casts = !(o.userData && o.userData.shadowlab && o.userData.shadowlab.casts_shadow === false);
    o.castShadow = casts;
    o.receiveShadow = true;
    counts.meshes++;
  });
  return counts;
}

// The shadow camera's fit. "bounds" (the default, what most apps do by hand): an orthographic box
// around the scene's bounding sphere, seen along the light. "fixed": a box of +-extent around the
// scene's centre. Spot and point lights keep three.js's own perspective shadow cameras.
function fitShadowCamera(scene, light, request) {
  const box = new THREE.Box3();
  scene.traverse((o) => {
    if (o.isMesh) box.expandByObject(o);
  });
  const sphere = box.getBoundingSphere(new THREE.Sphere());
  if (!light.isDirectionalLight) return sphere;
  // GLTFLoader puts the light's target at (0, 0, -1) in the light node: the light looks down -Z.
  light.target.updateMatrixWorld(true);
  const from = light.getWorldPosition(new THREE.Vector3());
  const direction = light.target.getWorldPosition(new THREE.Vector3()).sub(from).normalize();
  const r = Math.max(sphere.radius, 1e-6);
  const extent = request.fit === 'fixed' ? request.extent : r;
  // A light of our own at the scene's root: the loaded light's node may sit anywhere (a glTF
  // directional light has a direction only).
  light.parent.remove(light);
  const sun = new THREE.DirectionalLight(0xffffff, 1);
  sun.name = light.name;
  sun.position.copy(sphere.center).addScaledVector(direction, -2 * r);
  sun.target.position.copy(sphere.center);
  scene.add(sun);
  scene.add(sun.target);
  const cam = sun.shadow.camera;
  cam.left = -extent;
  cam.right = extent;
  cam.top = extent;
  cam.bottom = -extent;
  cam.near = r;
  cam.far = 3 * r;
  cam.updateProjectionMatrix();
  return { sun, sphere };
}

function unmaskedRenderer(gl) {
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  return info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
}

async function post(path, body) {
  await fetch(path, { method: 'POST', body });
}

async function main() {
  const request = await (await fetch('/request.json')).json();
  const gltf = await new GLTFLoader().loadAsync('/scene.glb');
  const scene = gltf.scene;
  scene.updateMatrixWorld(true);
  const { camera, width, height } = setUpCamera(gltf, request);
  let { light, others } = findLight(scene, request.light);
  for (const other of others) other.parent.remove(other);
  const counts = replaceMaterials(scene, request);
  const fit = fitShadowCamera(scene, light, request);
  if (fit.sun) light = fit.sun;
  scene.updateMatrixWorld(true);
  patchMaterials(scene, light);
  light.castShadow = true;
  light.shadow.mapSize.set(request.mapSize, request.mapSize);
  light.shadow.bias = request.bias;
  light.shadow.normalBias = request.normalBias;
  light.shadow.radius = request.radius;
  light.shadow.blurSamples = request.blurSamples;

  const canvas = document.createElement('canvas');
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false });
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.shadowMap.enabled = true;
  renderer.shadowMap.type = kShadowTypes[request.type];
  const gl = renderer.getContext();
  const target = new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType, depthBuffer: true });
  renderer.setRenderTarget(target);
  renderer.setClearColor(0x000000, 0);

  // The first render compiles the programs; each timed one after it is the frame's own work (the shadow
  // pass and the camera pass), not the compile.
  // A one-pixel read waits for the frame's work to be done (a finish alone need not, in a browser).
  const probe = new Float32Array(4);
  renderer.render(scene, camera);
  renderer.readRenderTargetPixels(target, 0, 0, 1, 1, probe);
  const times = [];
  for (let i = 0; i < request.repeat; i++) {
    const t0 = performance.now();
    renderer.render(scene, camera);
    renderer.readRenderTargetPixels(target, 0, 0, 1, 1, probe);
    times.push(performance.now() - t0);
  }
  times.sort((a, b) => a - b);

  const rgba = new Float32Array(width * height * 4);
  renderer.readRenderTargetPixels(target, 0, 0, width, height, rgba);
  // WebGL's rows run bottom-up; the frame contract's row 0 is the top.
  const vis = new Float32Array(width * height);
  const coverage = new Float32Array(width * height);
  for (let y = 0; y < height; y++) {
    const src = (height - 1 - y) * width;
    for (let x = 0; x < width; x++) {
      const p = (src + x) * 4;
      const covered = rgba[p] > 0.5;
      coverage[y * width + x] = covered ? 1 : 0;
      vis[y * width + x] = covered ? 1 - rgba[p + 3] : 0;
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
    frame_ms: times.length ? times[Math.floor(times.length / 2)] : null,
    frame_ms_all: times,
    meshes: counts.meshes,
    alpha_masked: counts.alphaMasked,
    three_revision: THREE.REVISION,
    gl_renderer: unmaskedRenderer(gl),
  };
  const header = new TextEncoder().encode(JSON.stringify(meta));
  const length = new Uint32Array([header.length]);
  await post('/result', new Blob([length, header, new Uint8Array(vis.buffer), new Uint8Array(coverage.buffer)]));
}

main().catch((e) => post('/error', String((e && e.message) || e)));
