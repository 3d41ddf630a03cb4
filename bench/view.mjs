// weft view's responsiveness in Debian's chromium (issue 44; docs/view.md):
//   node bench/view.mjs [--weft build/release/weft] [--before OLD/weft] [--size 256] [--spp 64]
//       [--out bench/results]
// A knit (fleece-colour, neural) served by `weft view`, looked at by a
// headless page: the time from the page's load to its first image, from a
// camera drag and from a colour change to the first image of the new view,
// refinements per second while nothing changes, the CPU the server uses
// once the page is closed and once the view reached its cap, and the A/B
// fiber layer's time per sample against the neural one's. Writes
// OUT/view.md and OUT/view.json. Not a test: no timing is asserted.
import { execFileSync } from 'node:child_process';
import { mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { launchBrowser, startView, waitForFrame } from '../tests/browser/view_lib.mjs';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const args = Object.fromEntries(process.argv.slice(2).reduce((pairs, a, i, all) =>
  (a.startsWith('--') ? pairs.concat([[a.slice(2), all[i + 1]]]) : pairs), []));
const weft = path.resolve(args.weft || path.join(root, 'build/release/weft'));
const size = Number(args.size || 256);
const spp = Number(args.spp || 64);
const outDir = path.resolve(args.out || path.join(root, 'bench/results'));
const work = path.join(root, 'bench/work/view');

const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2; };
// CPU seconds (user + system) of a process so far.
function cpuSeconds(pid) {
  const fields = readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' ');
  return (Number(fields[11]) + Number(fields[12])) / 100;  // utime, stime in clock ticks (USER_HZ 100)
}
async function cpuOver(pid, seconds) {
  const c0 = cpuSeconds(pid), t0 = Date.now();
  await new Promise((r) => setTimeout(r, seconds * 1000));
  return (cpuSeconds(pid) - c0) / ((Date.now() - t0) / 1000);
}

rmSync(work, { recursive: true, force: true });
mkdirSync(work, { recursive: true });
execFileSync(weft, ['scene', 'knit', '--model', path.join(root, 'models/fleece-colour.json'),
  '--width', String(size), '--height', String(size), '--spp', String(spp), '--out', path.join(work, 'knit')], { stdio: 'ignore' });
// Every measure of one binary's `weft view` in `browser`.
async function measure(browser, binary) {
  const view = await startView(binary, [path.join(work, 'knit/scene.json'), '--out', path.join(work, 'saved')]);
  const pid = view.process.pid;
  const result = { size, spp_cap: spp, cores: os.cpus().length, cpu: os.cpus()[0].model };
  try {
    // A page opened on the server: it has rendered its first samples and
    // waits (no page for 3 s). Then the same while it renders for another page.
    await new Promise((r) => setTimeout(r, 4000));
    const page = await browser.newPage({ viewport: { width: 1100, height: 800 } });
    // Three loads of the page, each after `pauseMs` away from it: the times to its first image.
    async function timeLoads(pauseMs) {
      const times = [];
      for (let i = 0; i < 3; i++) {
        await page.goto('about:blank');
        await new Promise((r) => setTimeout(r, pauseMs));
        const t0 = Date.now();
        await page.goto(view.url);
        await waitForFrame(page, 'neural', { spp: 0 });
        times.push(Date.now() - t0);
      }
      return times;
    }
    const loads = await timeLoads(4000);
    const other = await browser.newPage();
    await other.goto(view.url);
    await other.evaluate(() => send({ spp_cap: 65536 }));
    const busyLoads = await timeLoads(500);
    await other.close();
    await page.evaluate((cap) => send({ spp_cap: cap }), spp);
    result.first_image_busy_ms = median(busyLoads);
    result.first_image_ms = median(loads);

    // A camera drag, and a colour change: the time to the first image of the new view.
    // Colour i of the changes: red and blue in turn, by the count and not by
    // the picker's value (the page shows the colour the model reaches,
    // which a toggle on the value would send again: an edit that changes
    // nothing, whose next pass has the new generation anyway).
    async function timeEdit(action, i = 0) {
      return page.evaluate(async ([action, i]) => {
        const sleep = () => new Promise((r) => setTimeout(r, 1));
        const g0 = generation;
        const t0 = performance.now();
        if (action === 'orbit') orbit(12, 3);
        else {
          const input = document.querySelector('[data-role=appearance]');
          input.value = i % 2 ? '#2030c0' : '#c03020';
          input.dispatchEvent(new Event('input', { bubbles: true }));
        }
        while (generation === g0) await sleep();
        const g = generation;
        const img = document.getElementById('neural');
        // The first image of the new view: its samples start again.
        while (Number(img.dataset.generation) < g) await sleep();
        return [performance.now() - t0, Number(img.dataset.spp)];
      }, [action, i]);
    }
    const drags = [], colours = [];
    let restarted = 0;
    for (let i = 0; i < 8; i++) {
      const [ms, shownSpp] = await timeEdit('orbit');
      drags.push(ms);
      restarted += shownSpp <= 1;
      await page.waitForTimeout(400);
    }
    for (let i = 0; i < 6; i++) {
      const [ms, shownSpp] = await timeEdit('colour', i);
      colours.push(ms);
      restarted += shownSpp <= 1;
      await page.waitForTimeout(600);
    }
    // Every edit must have started the image again (else it measured a pass, not an edit).
    result.edits_restarted = `${restarted} of ${drags.length + colours.length}`;
    result.drag_to_image_ms = median(drags);
    result.colour_to_image_ms = median(colours);

    // Refinements per second while nothing changes (after a fresh view).
    await timeEdit('orbit');
    const refinements = await page.evaluate(async () => {
      const img = document.getElementById('neural');
      const seq0 = Number(img.dataset.seq), spp0 = Number(img.dataset.spp), t0 = performance.now();
      await new Promise((r) => setTimeout(r, 3000));
      return { frames: Number(img.dataset.seq) - seq0, spp: Number(img.dataset.spp) - spp0, seconds: (performance.now() - t0) / 1000 };
    });
    result.refinements_per_second = refinements.frames / refinements.seconds;
    result.spp_per_second = refinements.spp / refinements.seconds;
    const stats = await page.evaluate(() => fetch('/api/stats').then((r) => r.json()));
    result.neural_seconds_per_spp = stats.neural.seconds_per_spp;

    // At the cap: the CPU the server uses.
    await waitForFrame(page, 'neural', { spp, timeout: 600000 });
    result.cpu_at_cap = await cpuOver(pid, 3);

    // A/B: the fiber layer's time per sample (a few samples of each).
    await page.evaluate(() => send({ ab: true, spp_cap: 4 }));
    let ab;
    for (let i = 0; i < 600; i++) {
      ab = await page.evaluate(() => fetch('/api/stats').then((r) => r.json()));
      if (ab.status === 'done' && ab.fiber && ab.fiber.spp >= 4 && ab.ssim !== null) break;
      await page.waitForTimeout(1000);
    }
    result.fiber_seconds_per_spp = ab.fiber.seconds_per_spp;
    result.ab_neural_seconds_per_spp = ab.neural.seconds_per_spp;
    result.ab_ssim_at_4spp = ab.ssim;
    await page.evaluate(() => send({ ab: false, spp_cap: 65536 }));
    await page.waitForTimeout(1000);

    // The page closed while the view still refines: the server stops.
    result.cpu_rendering = await cpuOver(pid, 2);
    await page.close();
    await new Promise((r) => setTimeout(r, 4000));
    result.cpu_page_closed = await cpuOver(pid, 3);
  } finally {
    await view.stop();
  }
  return result;
}

const browser = await launchBrowser();
if (!browser) process.exit(77);
// With --before: that binary's measures too, alternating, the after binary last.
const before = args.before ? path.resolve(args.before) : null;
let result, resultBefore = null;
try {
  if (before) resultBefore = await measure(browser, before);
  result = await measure(browser, weft);
} finally {
  await browser.close();
}

// [measure, its value in a result, target]
const rows = [
  ['First image after the page loads', (r) => `${r.first_image_ms.toFixed(0)} ms`, '<= 300 ms'],
  ['The same while the server renders for another page', (r) => `${r.first_image_busy_ms.toFixed(0)} ms`, ''],
  ['New image after a camera drag', (r) => `${r.drag_to_image_ms.toFixed(0)} ms`, '<= 150 ms'],
  ['New image after a colour change', (r) => `${r.colour_to_image_ms.toFixed(0)} ms`, '<= 150 ms'],
  ['Refinements per second, nothing changing', (r) => r.refinements_per_second.toFixed(1), '>= 5'],
  ['Server CPU while refining (cores)', (r) => r.cpu_rendering.toFixed(2), ''],
  ['Server CPU at the spp cap (cores)', (r) => r.cpu_at_cap.toFixed(3), 'near 0'],
  ['Server CPU with the page closed (cores)', (r) => r.cpu_page_closed.toFixed(3), 'near 0'],
  ['Neural time per sample', (r) => `${(r.neural_seconds_per_spp * 1000).toFixed(0)} ms`, ''],
  ['Fiber / neural time per sample (A/B, one run)', (r) => (r.fiber_seconds_per_spp / r.ab_neural_seconds_per_spp).toFixed(1) + 'x', ''],
];
const header = resultBefore ? '| Measure | Before | Value | Target |\n| --- | --- | --- | --- |'
  : '| Measure | Value | Target |\n| --- | --- | --- |';
const table = rows.map(([name, value, target]) =>
  `| ${[name, ...(resultBefore ? [value(resultBefore)] : []), value(result), target].join(' | ')} |`).join('\n');
const md = `# weft view: responsiveness (bench/view.mjs)

A ${size} x ${size} knit (\`weft scene knit\`, models/fleece-colour.json, neural),
served by \`weft view\` and looked at by headless Debian chromium through
playwright-core, on ${result.cores} cores (${result.cpu}). Medians of 3 page loads, 8 drags
and 6 colour changes; CPU from /proc over 2-3 s windows. Targets of issue 44.${resultBefore ? `
*Before*: the binary given as --before, measured first in the same run.` : ''}

${header}
${table}

Samples per second while refining: ${result.spp_per_second.toFixed(1)}; SSIM of the
neural and fiber layers at 4 spp each (noise included): ${result.ab_ssim_at_4spp === null ? 'n/a' : result.ab_ssim_at_4spp.toFixed(3)}.
Edits whose first image started the samples again (each should): ${result.edits_restarted}${resultBefore ? ` (before: ${resultBefore.edits_restarted})` : ''}.

Command: \`node bench/view.mjs --size ${size} --spp ${spp}${resultBefore ? ' --before OLD/weft' : ''}\`
`;
mkdirSync(outDir, { recursive: true });
writeFileSync(path.join(outDir, 'view.md'), md);
writeFileSync(path.join(outDir, 'view.json'),
  JSON.stringify(resultBefore ? { ...result, before: resultBefore } : result, null, 2) + '\n');
console.log(md);
