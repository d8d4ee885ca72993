// Debian packages the tests, the CLI and the benchmarks need: Chromium (its
// SwiftShader Vulkan driver gives WebGPU without a GPU, for the page tests and
// for Dawn in Node) and the Vulkan loader. Installed with apt when running as
// root; otherwise we say exactly what to install.
import { execSync, spawnSync } from 'node:child_process';
import { existsSync, readdirSync } from 'node:fs';

const SWIFTSHADER_ICD = '/usr/lib/chromium/vk_swiftshader_icd.json';

function hasVulkanLoader() {
  const r = spawnSync('ldconfig', ['-p'], { encoding: 'utf8' });
  // The cache can list a library that was removed since: check the file.
  if (r.status === 0) return [...r.stdout.matchAll(/libvulkan\.so\.1 .*=> (\S+)/g)].some((m) => existsSync(m[1]));
  return ['/usr/lib/x86_64-linux-gnu/libvulkan.so.1', '/usr/lib/aarch64-linux-gnu/libvulkan.so.1', '/usr/lib64/libvulkan.so.1'].some((p) =>
    existsSync(p),
  );
}

/** A GPU device node (NVIDIA, or a DRM render node): Dawn can use its driver, no SwiftShader needed. */
export function hasGpuDeviceNodes() {
  if (existsSync('/dev/nvidia0')) return true;
  try {
    return readdirSync('/dev/dri').some((n) => n.startsWith('renderD'));
  } catch {
    return false;
  }
}

/** `chromium: false` when Chromium is not needed (Dawn on a machine with a GPU). */
export function missingSystemPackages({ chromium = true } = {}) {
  const missing = [];
  if (chromium && (!existsSync('/usr/bin/chromium') || !existsSync(SWIFTSHADER_ICD))) missing.push('chromium');
  if (!hasVulkanLoader()) missing.push('libvulkan1');
  return missing;
}

/**
 * Installs what is missing with apt-get when root; otherwise throws with the
 * command to run. `purpose` names who needs it, for the message.
 */
export function ensureSystemPackages({ chromium = true, purpose = 'the tests', quiet = false } = {}) {
  const missing = missingSystemPackages({ chromium });
  if (missing.length === 0) return;
  const isRoot = typeof process.getuid === 'function' && process.getuid() === 0;
  if (!isRoot || !existsSync('/usr/bin/apt-get')) {
    throw new Error(
      `Missing system packages for ${purpose}: ${missing.join(' ')}.\n` +
        `Install them with: sudo apt-get install -y ${missing.join(' ')}\n` +
        "(libvulkan1 is the Vulkan loader Dawn needs; Debian's chromium ships SwiftShader, the Vulkan driver used where there is no GPU.)",
    );
  }
  console.error(`[setup] installing Debian packages for ${purpose}: ${missing.join(' ')} (apt-get)...`);
  const env = { ...process.env, DEBIAN_FRONTEND: 'noninteractive' };
  const stdio = quiet ? ['ignore', 'ignore', 'inherit'] : 'inherit';
  execSync('apt-get update -qq', { stdio, env });
  execSync(`apt-get install -y -qq --no-install-recommends ${missing.join(' ')}`, { stdio, env });
}
