// The voxel size along x, y, z: taken from the file when it gives one (NRRD
// spacings or space directions, ImageJ calibration), else 1, and editable,
// since many raw CT and microscope volumes have thicker slices than pixels
// and look squashed without it.

/** World size of a voxel along x, y, z. */
export type Spacing = [number, number, number];

export class SpacingControl {
  private spacing: Spacing = [1, 1, 1];

  constructor(
    private readonly inputs: [HTMLInputElement, HTMLInputElement, HTMLInputElement],
    private readonly note: HTMLElement,
    private readonly onChange: (spacing: Spacing) => void,
  ) {
    for (const input of inputs) {
      input.addEventListener('change', () => {
        const values = inputs.map((i) => i.valueAsNumber);
        if (!values.every((v) => Number.isFinite(v) && v > 0)) {
          this.show();
          this.note.textContent = 'A voxel size must be a positive number.';
          return;
        }
        this.spacing = values as Spacing;
        this.note.textContent = 'set here';
        this.onChange(this.spacing);
      });
    }
  }

  get value(): Spacing {
    return this.spacing;
  }

  /** A new volume: its spacing from the file, or 1 when it gives none. */
  setVolume(fromFile: Spacing | undefined): void {
    this.spacing = fromFile ? [...fromFile] : [1, 1, 1];
    this.note.textContent = fromFile ? 'from the file' : 'the file gives none';
    this.show();
  }

  /** A size the user gave elsewhere (a link), over the file's. */
  setUserValue(spacing: Spacing): void {
    this.spacing = [...spacing];
    this.note.textContent = 'set by the link';
    this.show();
  }

  setEnabled(on: boolean): void {
    for (const input of this.inputs) input.disabled = !on;
  }

  private show(): void {
    this.inputs.forEach((input, a) => (input.value = String(Number(this.spacing[a].toPrecision(6)))));
  }
}
