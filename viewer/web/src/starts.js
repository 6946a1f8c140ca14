// Starting points (Fab Forms Sec. 7): a thumbnail button per point.
import * as THREE from 'three';
import { state, $ } from './state.js';
import { query, api, clearError } from './api.js';
import { formatValue } from './sliders.js';
import { requestUpdate } from './update.js';
import { meshFromGlb, fitCamera } from './preview.js';

export async function buildStarts() {
  const host = $('starts');
  host.textContent = '';
  if (!state.form.preview) return;
  const thumb = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  thumb.setSize(120, 120);
  const tScene = new THREE.Scene();
  tScene.background = new THREE.Color(0xf4f4f4);
  tScene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(1, 2, 1.5);
  tScene.add(sun);
  const tCamera = new THREE.PerspectiveCamera(40, 1, 0.1, 10000);
  for (const [i, start] of state.form.starting_points.entries()) {
    const button = document.createElement('button');
    button.dataset.index = i;
    button.title = start.u.map((v, d) => `${state.form.dimensions[d].name} ${formatValue(d, v)}`).join(', ');
    const img = document.createElement('img');
    img.alt = `starting point ${i + 1}`;
    button.appendChild(img);
    button.addEventListener('click', () => { clearError(); state.u = start.u.slice(); requestUpdate(); });
    host.appendChild(button);
    try {
      const buffer = await (await api('/api/preview.glb?' + query(start.u))).arrayBuffer();
      const group = await meshFromGlb(buffer);
      const holder = new THREE.Group();
      holder.add(group);
      tScene.add(holder);
      fitCamera(holder, tCamera, null);
      thumb.render(tScene, tCamera);
      img.src = thumb.domElement.toDataURL('image/png');
      tScene.remove(holder);
    } catch (e) { img.alt = String(e); }
  }
  thumb.dispose();
}
