import { state, $ } from './state.js';
import { query, api, setStatus, showError } from './api.js';

// ------------------------------------------------------------- download
async function download(format) {
  const res = await api(`/api/export?format=${format}&` + query(state.u));
  const bytes = new Uint8Array(await res.arrayBuffer());
  const name = (res.headers.get('Content-Disposition') ?? '').match(/filename="([^"]+)"/)?.[1] ?? `design.${format}`;
  state.download = { name, format, size: bytes.length };
  const a = document.createElement('a');
  a.href = URL.createObjectURL(new Blob([bytes], { type: res.headers.get('Content-Type') }));
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 60000);
  setStatus(`downloaded ${name} (${(bytes.length / 1024).toFixed(0)} KiB, ${res.headers.get('X-Triangles')} triangles, voxel ${Number(res.headers.get('X-Voxel-Size')).toFixed(3)} mm)`);
}

export function buildDownloads() {
  for (const format of ['stl', '3mf']) {
    const b = $('download-' + format);
    b.addEventListener('click', () => {
      b.disabled = true;
      download(format).catch(showError).finally(() => { b.disabled = false; });
    });
  }
}
