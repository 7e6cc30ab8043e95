// The web view in a real browser (`symb run --view`): Debian's chromium driven headless by npm's
// playwright-core (both installed by scripts/setup). Two runs at real-time speed, side by side:
//   maze:  the robot moves (its position in the page changes); a `hook` typed into the page's
//          shell appears in the page's hook table, with its priority; a wrong token is refused
//   ahhs:  the hormone controller's levels appear among the probes
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

const out = fs.mkdtempSync(path.join(os.tmpdir(), 'symb-view-'));
const children = [];

function fail(message) {
  console.error(`FAIL: ${message}`);
  process.exitCode = 1;
}

// Starts `symb run SCENARIO --view 0` and resolves with the URL it prints.
function startRun(scenario, extra = []) {
  const child = spawn(symb, ['run', path.join(scenarios, scenario), '--view', '0', '--speed', '1', '--duration', '60s',
                             '--quiet', '--out', path.join(out, scenario), ...extra],
                      { stdio: ['ignore', 'ignore', 'pipe'] });
  children.push(child);
  return new Promise((resolve, reject) => {
    let err = '';
    child.stderr.on('data', (d) => {
      err += d;
      const m = err.match(/view: (http:\/\/\S+)/);
      if (m) resolve(m[1]);
    });
    child.on('exit', (code) => reject(new Error(`symb run ${scenario} ended (${code}) before its view: ${err}`)));
    setTimeout(() => reject(new Error(`no view URL from symb run ${scenario}: ${err}`)), 5000);
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

(async () => {
  const [mazeUrl, ahhsUrl] = await Promise.all([startRun('maze.yaml'), startRun('ahhs_obstacle_avoidance.yaml')]);
  const args = process.getuid && process.getuid() === 0 ? ['--no-sandbox'] : [];
  const browser = await chromium.launch({ executablePath: chromiumPath, args, headless: true });
  try {
    const maze = await browser.newPage();
    await maze.goto(mazeUrl);
    await check('the maze run\'s robot moves in the page', async () => {
      await maze.waitForFunction(() => document.getElementById('robot-pos').textContent.startsWith('x '),
                                 null, { timeout: 10000 });
      const first = await maze.textContent('#robot-pos');
      await maze.waitForFunction((p) => document.getElementById('robot-pos').textContent !== p, first,
                                 { timeout: 10000 });
      const second = await maze.textContent('#robot-pos');
      console.log(`  position ${first} -> ${second}`);
    });
    await check('a hook typed into the page\'s shell appears in the hook table', async () => {
      await maze.waitForSelector('#hooks tbody tr[data-hook="ir->controller"]', { timeout: 10000 });
      // The scenario hooks ir -> controller at priority 0: rewired at priority 7, the row is new.
      const withPriority7 = () => [...document.querySelectorAll('#hooks tbody tr[data-hook="ir->controller"]')]
        .filter((tr) => tr.cells[3].textContent === '7').length;
      if (await maze.evaluate(withPriority7)) throw new Error('the hook is there before it was made');
      await maze.fill('#shell-input', 'unhook ir controller');
      await maze.press('#shell-input', 'Enter');
      await maze.fill('#shell-input', 'hook ir controller --priority 7');
      await maze.press('#shell-input', 'Enter');
      await maze.waitForFunction(withPriority7, null, { timeout: 10000 })
        .catch(async (e) => { throw new Error(`${e.message.split('\n')[0]}; the shell said ${JSON.stringify(await maze.textContent('#shell-output'))}`); });
      await maze.waitForFunction(() => document.getElementById('shell-output').textContent.includes('hook'), null,
                                 { timeout: 10000 });
      console.log(`  shell: ${JSON.stringify(await maze.textContent('#shell-output'))}`);
    });
    await check('pause stops the clock; resume goes on', async () => {
      await maze.click('#pause');
      await maze.waitForFunction(() => document.body.dataset.paused === 'true', null, { timeout: 10000 });
      const t0 = await maze.textContent('#clock');
      await maze.waitForTimeout(400);
      const t1 = await maze.textContent('#clock');
      if (t0 !== t1) throw new Error(`the clock went on while paused: ${t0} -> ${t1}`);
      await maze.click('#pause');
      await maze.waitForFunction((t) => document.getElementById('clock').textContent !== t, t1, { timeout: 10000 });
    });
    await check('a wrong token is refused', async () => {
      const bad = await browser.newPage();
      await bad.goto(mazeUrl.replace(/token=[^&]*/, 'token=0123456789abcdef'));
      await bad.waitForFunction(() => document.getElementById('conn').textContent.startsWith('refused'), null,
                                { timeout: 10000 });
      if (await bad.$('#tasks tbody tr')) throw new Error('a refused page shows tasks');
    });
    await check('the AHHS run\'s hormone levels appear among the probes', async () => {
      const ahhs = await browser.newPage();
      await ahhs.goto(ahhsUrl);
      const probe = await ahhs.waitForSelector('#probes .probe', { timeout: 10000 });
      const label = await probe.getAttribute('data-probe');
      const values = await probe.$eval('.values', (e) => e.textContent);
      console.log(`  ${label}: ${values}`);
      if (!/hormone/.test(label)) throw new Error(`the first probe is ${label}, not hormone levels`);
      if (!values.split(' ').some((v) => Number(v) > 0)) throw new Error(`no hormone level above 0: ${values}`);
    });
  } finally {
    await browser.close();
    for (const c of children) c.kill('SIGTERM');
    fs.rmSync(out, { recursive: true, force: true });
  }
})().catch((e) => {
  fail(e.message);
  for (const c of children) c.kill('SIGTERM');
});
