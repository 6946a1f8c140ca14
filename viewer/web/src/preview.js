// The 3-D preview (three.js): the glb of the design at the point, or of its
// snapped sample, and the camera fitted to it.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { state, $ } from './state.js';
import { query, api, setStatus } from './api.js';
import { formatValue } from './sliders.js';

export let renderer, scene, camera, controls, modelGroup;
let fittedSize = 0;
const loader = new GLTFLoader();
export const material = new THREE.MeshStandardMaterial({ color: 0xd9b38c, roughness: 0.6, metalness: 0.05 });

export function initView() {
  const host = $('preview');
  renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(host.clientWidth, host.clientHeight);
  host.appendChild(renderer.domElement);
  scene = new THREE.Scene();
  scene.background = new THREE.Color(0xffffff);
  camera = new THREE.PerspectiveCamera(40, host.clientWidth / host.clientHeight, 0.1, 10000);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(1, 2, 1.5);
  scene.add(sun);
  controls = new OrbitControls(camera, renderer.domElement);
  controls.addEventListener('change', render);
  modelGroup = new THREE.Group();  // glTF is metres, +Y up (artifact/glb.h)
  scene.add(modelGroup);
  window.addEventListener('resize', () => {
    renderer.setSize(host.clientWidth, host.clientHeight);
    camera.aspect = host.clientWidth / host.clientHeight;
    camera.updateProjectionMatrix();
    render();
  });
}

export function render() { renderer.render(scene, camera); }

function parseGlb(buffer) {
  return new Promise((resolve, reject) => loader.parse(buffer, '', resolve, reject));
}

export async function meshFromGlb(buffer) {
  const gltf = await parseGlb(buffer);
  const group = new THREE.Group();
  gltf.scene.traverse((o) => {
    if (o.isMesh) {
      // Exact meshes carry normals split at creases (flat faces, sharp
      // edges); level-set surfaces get smooth ones here.
      if (!o.geometry.attributes.normal) o.geometry.computeVertexNormals();
      // A part an OpenSCAD model coloured (material "part NAME", its
      // color() in baseColorFactor) keeps its colour and opacity.
      const own = o.material;
      if (own?.name?.startsWith('part ')) {
        o.material = material.clone();
        o.material.color.copy(own.color);
        o.material.opacity = own.opacity;
        o.material.transparent = own.transparent;
      } else o.material = material;
      group.add(o.clone());
    }
  });
  return group;
}

export function fitCamera(object, cam, ctl) {
  const box = object.isBox3 ? object : new THREE.Box3().setFromObject(object);
  const size = box.getSize(new THREE.Vector3()).length() || 1;
  const centre = box.getCenter(new THREE.Vector3());
  cam.position.copy(centre).add(new THREE.Vector3(0.6, 0.45, 0.9).multiplyScalar(size * 1.1));
  cam.near = size / 100;
  cam.far = size * 100;
  cam.updateProjectionMatrix();
  if (ctl) { ctl.target.copy(centre); ctl.update(); } else cam.lookAt(centre);
}

let previewSeq = 0;
// exact: ask for the design at exactly u; the server answers it when it is
// expected to fit its budget, else the snapped sample's (docs/viewer.md,
// Exact previews). The label under the view says which is shown.
export async function loadPreview(u, sample, exact = false) {
  if (!state.form.preview) return;
  if (exact ? query(u) === state.previewQuery : sample === state.previewSample && state.previewKind === 'snapped') return;
  const seq = ++previewSeq;
  const res = await api('/api/preview.glb?' + query(u) + (exact ? '&exact=1' : ''));
  const buffer = await res.arrayBuffer();
  if (seq !== previewSeq) return;
  const kind = res.headers.get('X-Preview');
  const label = () => showPreviewKind(kind, res.headers.get('X-Preview-U'), res.headers.get('X-Preview-Fallback'));
  if (kind === 'snapped' && state.previewKind === 'snapped' && Number(res.headers.get('X-Sample')) === state.previewSample) {
    label();  // the snapped sample on screen already
    return;
  }
  const group = await meshFromGlb(buffer);
  if (seq !== previewSeq) return;
  modelGroup.clear();
  modelGroup.add(group);
  // Refit the camera when the model's size changes a lot (keeps the user's
  // orbit otherwise).
  const size = new THREE.Box3().setFromObject(modelGroup).getSize(new THREE.Vector3()).length();
  if (!fittedSize || size > 1.25 * fittedSize || size < 0.5 * fittedSize) {
    fitCamera(modelGroup, camera, controls);
    fittedSize = size;
  }
  render();
  state.previewSample = Number(res.headers.get('X-Sample'));
  state.previewKind = kind;
  state.previewQuery = kind === 'exact' ? query(u) : null;
  state.previewCount += 1;
  label();
  setStatus(`${kind === 'exact' ? 'exact point' : `sample #${state.previewSample}`} · preview ${(Number(res.headers.get('X-Preview-Seconds')) * 1000).toFixed(0)} ms` +
    ` · cached subtrees ${res.headers.get('X-Cache-Hits')} (${state.form.cache})`);
}

// "exact point" or "nearest sample (values)", from the preview's headers.
function showPreviewKind(kind, shown, fallback) {
  const u = shown ? shown.split(',').map(Number) : [];
  const values = u.map((v, d) => `${state.form.dimensions[d]?.name} ${formatValue(d, v)}`).join(', ');
  const label = $('preview-kind');
  label.textContent = state.form.dimensions.length === 0 ? 'the model (nothing to customise)'
    : kind === 'exact' ? 'exact point' : `nearest sample (${values})`;
  label.title = kind === 'exact' ? 'the design evaluated at exactly these values; validity is the form\'s'
    : fallback === 'budget' ? 'an exact preview would take longer than the server\'s budget'
    : fallback === 'failed' ? 'the design could not be evaluated at exactly these values'
    : 'previews snap to the closest valid sample';
}
