// What the viewer draws (src/render/viewer.ts): each layer records its draws into the frame's
// passes; see-through content goes through the depth peeling (depth-peel.ts).
export interface RenderLayer {
  /** Records draws into the frame's render pass (group 0 = frame uniforms is already set): the opaque part. */
  draw(pass: GPURenderPassEncoder): void;
  /** Has see-through content this frame (drawn by drawPeel, not draw). */
  readonly transparent?: boolean;
  /** The see-through part, once per depth-peel pass (group 0 the frame, group 2 the peel's depths: src/render/depth-peel.ts). */
  drawPeel?(pass: GPURenderPassEncoder): void;
}
