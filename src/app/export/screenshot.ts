// The view as a PNG: draw a frame and read the canvas in the same task (a
// WebGPU canvas keeps its current texture until the task ends).
import type { Viewer } from '../../render/viewer.ts';

export function captureViewPng(viewer: Viewer): Promise<Blob> {
  viewer.drawNow();
  return new Promise((resolve, reject) => {
    viewer.canvas.toBlob((blob) => (blob ? resolve(blob) : reject(new Error('the browser could not encode the view as PNG'))), 'image/png');
  });
}
