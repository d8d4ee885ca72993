// What the fuzz suite needs to know about one reader: valid files to mutate,
// the function the page and the CLI call to open a file, and how to tell a
// clean rejection (the reader's own error, naming the file) from a crash.

export interface FuzzSeed {
  name: string;
  bytes: Uint8Array;
}

export interface FuzzTarget {
  /** Short reader name for the table: 'zfp', 'raw', 'nrrd', 'tiff', 'las', 'swc'. */
  reader: string;
  /** Valid files (from ../shared/data or generated) that mutations start from. */
  seeds(): Promise<FuzzSeed[]>;
  /**
   * Opens one file the way the page and the CLI do; resolves when accepted
   * (returning a short summary for the report), throws the reader's error when rejected.
   */
  open(name: string, bytes: Uint8Array): Promise<unknown>;
  /** True when `e` is the reader's own error and its message names `name`. */
  isCleanRejection(e: unknown, name: string): boolean;
}
