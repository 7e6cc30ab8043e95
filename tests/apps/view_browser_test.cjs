// The web view in a real browser (`symb run --view`, `symb evolve --view`, `symb board --view`):
// Debian's chromium driven headless by npm's playwright-core (both installed by scripts/setup).
// Six runs, paced to the wall clock, started together; their pages are checked in three waves of
// two or three (each wave's pages closed, its runs stopped, before the next opens): a page costs
// headless chromium a third to half of a core while it is open (its renderer and its compositor,
// 20 frames a second), so six at once outran two cores on a slow box and every wait timed out:
//   maze:  the robot moves (its position in the page changes); a `hook` typed into the page's
//          shell appears in the page's hook table, with its priority; a wrong token is refused
//   ahhs:  the hormone controller's levels appear among the probes, with a plot over time
//   linda: the spiking network's raster gains spikes
//   caterpillar: the 3D organism's five modules are drawn and move; four docked pairs are listed
//   evolve: the fitness plot gains points as evaluations end
//   board: a board (over `symb link`'s lines, no simulator) shows its tasks and no world
// No page may throw.
// Run by ctest through view_browser_test.sh, which skips (77) when node, chromium or
// playwright-core is missing.
//   node view_browser_test.cjs SYMB_BINARY SCENARIO_DIR PLAYWRIGHT_DIR CHROMIUM
'use strict';

const { spawn } = require('child_process');
const fs = require('fs');
const os = require('os');
const path = require('path');

const [symb, scenarios, playwrightDir, chromiumPath] = process.argv.slice(2);
const { chromium } = require(path.join(playwrightDir, 'node_modules', 'playwright-core'));

// How long a page may take to show what is checked: generous, for a loaded CI box (a passing run
// takes a fraction of it).
const kWait = 20000;
const out = fs.mkdtempSync(path.join(os.tmpdir(), 'symb-view-'));
const children = new Map();  // what a process was started for -> the process

function fail(message) {
  console.error(`FAIL: ${message}`);
  process.exitCode = 1;
}

// Starts `symb run SCENARIO --view 0` and resolves with the URL it prints.
function startRun(scenario, extra = []) {
  return startSymb(['run', path.join(scenarios, scenario), '--view', '0', '--speed', '1', '--duration', '120s',
                    '--quiet', '--out', path.join(out, scenario), ...extra], scenario);
}

// Starts `symb ARGS` and resolves with the view URL it prints (on stderr or stdout).
function startSymb(args, what) {
  const child = spawn(symb, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  children.set(what, child);
  const scenario = what;
  return new Promise((resolve, reject) => {
    let err = '';
    child.stdout.on('data', (d) => { err += d; });
    child.stderr.on('data', (d) => {
      err += d;
      const m = err.match(/view: (http:\/\/\S+)/);
      if (m) resolve(m[1]);
    });
    child.on('exit', (code) => reject(new Error(`symb ${scenario} ended (${code}) before its view: ${err}`)));
    // unref: a pending timer would keep the test alive after its last check.
    setTimeout(() => reject(new Error(`no view URL from symb ${scenario}: ${err}`)), kWait).unref();
  });
}

async function check(name, fn) {
  try {
    await fn();
    console.log(`ok: ${name}`);
  } catch (e) {
    fail(`${name}: ${e.message}`);
  }
}

// `symb link` (two pseudo-terminal lines) and `symb board` on the board's line, with its view.
async function startBoard() {
  const tty = path.join(out, 'tty');
  const link = spawn(symb, ['link', '--dir', tty], { stdio: 'ignore' });
  children.set('link', link);
  for (let i = 0; i < 250 && !fs.existsSync(path.join(tty, 'shell')); ++i) await new Promise((r) => setTimeout(r, 20));
  return startSymb(['board', path.join(scenarios, 'maze.yaml'), '--serial', path.join(tty, 'board'), '--view', '0',
                    '--duration', '60s', '--quiet'], 'board');
}

// A page that fails the test when its script throws.
async function open(browser, url, name) {
  const page = await browser.newPage();
  page.on('pageerror', (e) => fail(`${name}'s page threw: ${e.message}`));
  await page.goto(url);
  return page;
}

// Opens the pages of `urls` (name -> URL) together, runs the checks `checks(pages)` returns side
// by side, then closes the pages.
async function wave(browser, urls, checks) {
  const names = Object.keys(urls);
  const pages = Object.fromEntries(
    await Promise.all(names.map(async (n) => [n, await open(browser, urls[n], n)])));
  try {
    await Promise.all(checks(pages));
  } finally {
    await Promise.all(names.map((n) => pages[n].close()));
  }
}

// The runs started for `whats` are done with: they stop, so that the next wave has the cores.
function stop(...whats) {
  for (const w of whats) children.get(w)?.kill('SIGKILL');
}

(async () => {
  // The browser starts while the runs do.
  const args = process.getuid && process.getuid() === 0 ? ['--no-sandbox'] : [];
  const [browser, mazeUrl, ahhsUrl, lindaUrl, caterpillarUrl, evolveUrl, boardUrl] = await Promise.all([
    chromium.launch({ executablePath: chromiumPath, args, headless: true }),
    startRun('maze.yaml'), startRun('ahhs_obstacle_avoidance.yaml'), startRun('linda_maze.yaml'),
    startRun('caterpillar.yaml'),
    startSymb(['evolve', path.join(scenarios, 'evolve_maze.yaml'), '--view', '0', '--speed', '100', '--quiet',
               '--checkpoint-every', '0', '--out', path.join(out, 'evolve')], 'evolve_maze.yaml'),
    startBoard()]);
  try {
    // The first wave: the maze's checks one after the other (they share its page), a refused page
    // beside them (it gets no frames) and the board.
    await wave(browser, { maze: mazeUrl, board: boardUrl }, ({ maze, board }) => [
      (async () => {
        await check('the maze run\'s robot moves in the page', async () => {
          await maze.waitForFunction(() => document.getElementById('robot-pos').textContent.startsWith('x '),
                                     null, { timeout: kWait });
          const first = await maze.textContent('#robot-pos');
          await maze.waitForFunction((p) => document.getElementById('robot-pos').textContent !== p, first,
                                     { timeout: kWait });
          const second = await maze.textContent('#robot-pos');
          console.log(`  position ${first} -> ${second}`);
        });
        await check('a hook typed into the page\'s shell appears in the hook table', async () => {
          await maze.waitForSelector('#hooks tbody tr[data-hook="ir->controller"]', { timeout: kWait });
          // The scenario hooks ir -> controller at priority 0: rewired at priority 7, the row is new.
          const withPriority7 = () => [...document.querySelectorAll('#hooks tbody tr[data-hook="ir->controller"]')]
            .filter((tr) => tr.cells[3].textContent === '7').length;
          if (await maze.evaluate(withPriority7)) throw new Error('the hook is there before it was made');
          await maze.fill('#shell-input', 'unhook ir controller');
          await maze.press('#shell-input', 'Enter');
          await maze.fill('#shell-input', 'hook ir controller --priority 7');
          await maze.press('#shell-input', 'Enter');
          await maze.waitForFunction(withPriority7, null, { timeout: kWait })
            .catch(async (e) => { throw new Error(`${e.message.split('\n')[0]}; the shell said ${JSON.stringify(await maze.textContent('#shell-output'))}`); });
          await maze.waitForFunction(() => document.getElementById('shell-output').textContent.includes('hook'), null,
                                     { timeout: kWait });
          console.log(`  shell: ${JSON.stringify(await maze.textContent('#shell-output'))}`);
        });
        await check('pause stops the clock; resume goes on', async () => {
          await maze.click('#pause');
          await maze.waitForFunction(() => document.body.dataset.paused === 'true', null, { timeout: kWait });
          await maze.waitForTimeout(200);  // a frame made before the pause took hold may still come
          const t0 = await maze.textContent('#clock');
          await maze.waitForTimeout(400);
          const t1 = await maze.textContent('#clock');
          if (t0 !== t1) throw new Error(`the clock went on while paused: ${t0} -> ${t1}`);
          await maze.click('#pause');
          await maze.waitForFunction((t) => document.getElementById('clock').textContent !== t, t1, { timeout: kWait });
        });
      })(),
      check('a wrong token is refused', async () => {
        const bad = await browser.newPage();
        try {
          await bad.goto(mazeUrl.replace(/token=[^&]*/, 'token=0123456789abcdef'));
          await bad.waitForFunction(() => document.getElementById('conn').textContent.startsWith('refused'), null,
                                    { timeout: kWait });
          if (await bad.$('#tasks tbody tr')) throw new Error('a refused page shows tasks');
        } finally {
          await bad.close();
        }
      }),
      check('a board shows its tasks and no world', async () => {
        await board.waitForSelector('#tasks tbody tr[data-task="controller"]', { timeout: kWait });
        if (await board.evaluate(() => document.body.dataset.world) !== 'none') throw new Error('a board with a world');
        if (!await board.isVisible('#no-world')) throw new Error('the page does not say there is no world');
      }),
    ]);
    stop('maze.yaml', 'board', 'link');
    await wave(browser, { ahhs: ahhsUrl, linda: lindaUrl }, ({ ahhs, linda }) => [
      check('the AHHS run\'s hormone levels appear among the probes', async () => {
        const probe = await ahhs.waitForSelector('#probes .probe', { timeout: kWait });
        const label = await probe.getAttribute('data-probe');
        const values = await probe.$eval('.values', (e) => e.textContent);
        console.log(`  ${label}: ${values}`);
        if (!/hormone/.test(label)) throw new Error(`the first probe is ${label}, not hormone levels`);
        if (!values.split(' ').some((v) => Number(v) > 0)) throw new Error(`no hormone level above 0: ${values}`);
        // Its plot over time gains points.
        await ahhs.waitForFunction((k) => Number(document.querySelector(`#probes .probe[data-probe="${k}"]`).dataset.points) >= 3,
                                   label, { timeout: kWait });
      }),
      check('the spiking network\'s raster gains spikes', async () => {
        await linda.waitForSelector('#spikes .raster', { timeout: kWait });
        const spikes = () => Number(document.querySelector('#spikes .raster').dataset.spikes);
        const first = await linda.evaluate(spikes);
        await linda.waitForFunction((n) => Number(document.querySelector('#spikes .raster').dataset.spikes) > n, first,
                                    { timeout: kWait });
        console.log(`  ${first} -> ${await linda.evaluate(spikes)} spikes`);
      }),
    ]);
    stop('ahhs_obstacle_avoidance.yaml', 'linda_maze.yaml');
    await wave(browser, { caterpillar: caterpillarUrl, evolve: evolveUrl }, ({ caterpillar, evolve }) => [
      check('the 3D organism\'s modules are drawn and move', async () => {
        await caterpillar.waitForFunction(() => document.body.dataset.world === '3d' &&
                                          document.getElementById('robot-pos').textContent.startsWith('x '),
                                          null, { timeout: kWait });
        if (await caterpillar.$eval('#world', (c) => c.dataset.modules) !== '5') throw new Error('not five modules');
        const first = await caterpillar.textContent('#robot-pos');
        await caterpillar.waitForFunction((p) => document.getElementById('robot-pos').textContent !== p, first,
                                          { timeout: kWait });
        console.log(`  module m0 ${first} -> ${await caterpillar.textContent('#robot-pos')}`);
        const pairs = await caterpillar.$eval('#topology', (e) => e.dataset.pairs);
        if (pairs !== '4') throw new Error(`${pairs} docked pairs listed, not 4`);
        // Painted: many pixels of the canvas are not blank (the world is drawn at the page's next
        // animation frame after a frame from the run; one has come since the first position).
        const painted = await caterpillar.$eval('#world', (c) => {
          const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
          let n = 0;
          for (let i = 3; i < d.length; i += 4) n += d[i] > 0 ? 1 : 0;
          return n;
        });
        if (painted < 2000) throw new Error(`only ${painted} pixels drawn`);
      }),
      check('the evolution\'s fitness plot gains points', async () => {
        await evolve.waitForFunction(() => Number(document.getElementById('fitness').dataset.points) > 0, null,
                                     { timeout: kWait });
        const first = Number(await evolve.$eval('#fitness', (c) => c.dataset.points));
        await evolve.waitForFunction((n) => Number(document.getElementById('fitness').dataset.points) > n, first,
                                     { timeout: kWait });
        console.log(`  ${first} -> ${await evolve.$eval('#fitness', (c) => c.dataset.points)} points`);
      }),
    ]);
  } finally {
    await browser.close();
    for (const c of children.values()) c.kill('SIGKILL');  // their files are not wanted: no need to wait for them
    fs.rmSync(out, { recursive: true, force: true });
  }
})().catch((e) => {
  fail(e.message);
  for (const c of children.values()) c.kill('SIGKILL');
});
