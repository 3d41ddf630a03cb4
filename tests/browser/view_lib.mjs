// Shared by view_test.mjs and bench/view.mjs: Debian's chromium through
// playwright-core, a `weft view` process, and reading the page's frames.
import { spawn } from 'node:child_process';
import { existsSync } from 'node:fs';

export const chromiumPath = process.env.WEFT_CHROMIUM || '/usr/bin/chromium';

// The browser, or null (with the reason on stderr) when chromium or
// playwright-core is not installed: the caller skips.
export async function launchBrowser() {
  if (!existsSync(chromiumPath)) {
    console.error(`skipped: no chromium at ${chromiumPath} (apt-get install chromium; scripts/test does)`);
    return null;
  }
  let chromium;
  try {
    ({ chromium } = await import('playwright-core'));
  } catch (e) {
    console.error('skipped: playwright-core is not installed (npm ci in tests/browser; scripts/test does)');
    return null;
  }
  // The flags a closed network needs (no background connections), and no
  // sandbox (CI runs as root).
  return chromium.launch({
    executablePath: chromiumPath,
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
}

// Starts `weft view ARGS --port 0` and resolves with {url, process, stop()}
// once it prints its address.
export function startView(weft, args) {
  return new Promise((resolve, reject) => {
    const child = spawn(weft, ['view', ...args, '--port', '0'], { stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '', err = '';
    const timer = setTimeout(() => { child.kill('SIGKILL'); reject(new Error('weft view did not start: ' + err)); }, 120000);
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/(http:\/\/[^\s]+\/)/);
      if (m) {
        clearTimeout(timer);
        resolve({
          url: m[1],
          process: child,
          stderr: () => err,
          stop: () => new Promise((done) => {
            if (child.exitCode !== null) { done(child.exitCode); return; }
            child.on('exit', (code) => done(code));
            child.kill('SIGINT');
          }),
        });
      }
    });
    child.stderr.on('data', (d) => { err += d; });
    child.on('exit', (code) => { clearTimeout(timer); reject(new Error(`weft view exited ${code}: ${err}`)); });
  });
}

// Waits until the layer's <img> shows a frame with at least `spp` samples
// of an edit at least `generation`; resolves with its data attributes.
export async function waitForFrame(page, layer, { spp = 1, generation = 0, timeout = 120000 } = {}) {
  await page.waitForFunction(({ layer, spp, generation }) => {
    const img = document.getElementById(layer);
    return img && img.dataset.spp !== undefined && Number(img.dataset.spp) >= spp &&
      Number(img.dataset.generation) >= generation && img.complete && img.naturalWidth > 0;
  }, { layer, spp, generation }, { timeout, polling: 20 });
  return page.evaluate((layer) => Object.assign({}, document.getElementById(layer).dataset), layer);
}

// The layer's image drawn at 96 x 96: mean and standard deviation of its
// channel values in [0, 1], and with `withPixels` its RGBA bytes.
export async function imageStats(page, layer, withPixels = false) {
  return page.evaluate(({ layer, withPixels }) => {
    const img = document.getElementById(layer);
    const canvas = document.createElement('canvas');
    canvas.width = 96; canvas.height = 96;
    const ctx = canvas.getContext('2d');
    ctx.drawImage(img, 0, 0, 96, 96);
    const data = ctx.getImageData(0, 0, 96, 96).data;
    let sum = 0, sum2 = 0, n = 0;
    for (let i = 0; i < data.length; i += 4)
      for (let c = 0; c < 3; c++) { const v = data[i + c] / 255; sum += v; sum2 += v * v; n++; }
    const mean = sum / n;
    return { mean, std: Math.sqrt(Math.max(0, sum2 / n - mean * mean)), pixels: withPixels ? Array.from(data) : undefined };
  }, { layer, withPixels });
}
