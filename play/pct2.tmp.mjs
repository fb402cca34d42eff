import { readFileSync } from 'node:fs';
import { execFileSync } from 'node:child_process';
import { Nano } from './sim/nano.js';
import { runScenario } from './test/support/runner.js';
const file = process.argv[2];
const scenario = JSON.parse(readFileSync(file, 'utf8'));
const simavr = JSON.parse(execFileSync('../target/debug/simtrace', [file], { maxBuffer: 1 << 28 }));
let keep; const orig = Nano.prototype.runUntil; Nano.prototype.runUntil = function(e){ keep=this; return orig.call(this,e); };
const origReset = Nano.prototype.reset; Nano.prototype.reset = function(){ keep=this; return origReset.call(this); };
runScenario(scenario, readFileSync('../out/m328-nano-utile.hex','utf8'), simavr);
const out=[];
for (let i = 0; i < Number(process.argv[3]); i++) { const cpu = keep.chip.cpu; out.push(`${(cpu.pc*2).toString(16)} ${cpu.cycles}`); keep.runUntil(cpu.cycles + 1); }
console.log(out.join('\n'));
