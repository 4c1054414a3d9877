// The omis Flamenco job type (scripts/flamenco/omis_bake.js) compiled under
// node with a stub of Flamenco's author API, on a recorded job submission:
// every lightmap tile is in exactly one task, each range's compose task
// depends on exactly that unit's ranges, and the commands are the omis
// command line's. Bad settings are refused with a message.
"use strict";
const assert = require("assert");
const fs = require("fs");
const path = require("path");
const { compile } = require("./flamenco_stub.js");

const script = path.join(__dirname, "..", "..", "scripts", "flamenco", "omis_bake.js");
const recorded = JSON.parse(fs.readFileSync(path.join(__dirname, "recorded_job.json"), "utf8"));
let checks = 0;
const check = (fn) => { fn(); ++checks; };

const { jobType, tasks } = compile(script, recorded);
check(() => assert.strictEqual(jobType.label, "omis Bake"));
check(() => assert.deepStrictEqual(jobType.settings.map((s) => s.key),
                                   ["job_file", "units", "tiles_per_task", "python"]));

const units = JSON.parse(recorded.settings.units);
const perTask = recorded.settings.tiles_per_task;
const job = recorded.settings.job_file;
units.forEach((unit, k) => {
    const prefix = `bake-${k}-${unit.object}`;
    if (unit.kind == "corner") {
        const mine = tasks.filter((t) => t.name == prefix);
        check(() => assert.strictEqual(mine.length, 1));
        check(() => assert.deepStrictEqual(mine[0].commands[0].parameters.args,
                                           ["-m", "omis", "bake", job, "--unit", `${k}`]));
        return;
    }
    const ranges = tasks.filter((t) => t.name.startsWith(prefix + "-tiles-"));
    const tiles = Math.ceil(unit.width / 16) * Math.ceil(unit.height / 16);
    const seen = new Array(tiles).fill(0);
    for (const t of ranges) {
        const args = t.commands[0].parameters.args;
        check(() => assert.deepStrictEqual(args.slice(0, 6), ["-m", "omis", "bake", job, "--unit", `${k}`]));
        check(() => assert.strictEqual(args[6], "--tiles"));
        const [first, count] = args[7].split(":").map(Number);
        check(() => assert.ok(count >= 1 && count <= perTask && first % perTask == 0));
        for (let i = first; i < first + count; ++i) seen[i] += 1;
        check(() => assert.strictEqual(t.commands[0].parameters.exe, "python3"));
        check(() => assert.strictEqual(t.type, "misc"));
    }
    check(() => assert.ok(seen.every((n) => n == 1), `unit ${k}: every tile in exactly one task`));
    const compose = tasks.filter((t) => t.name == `compose-${k}-${unit.object}`);
    check(() => assert.strictEqual(compose.length, 1));
    check(() => assert.deepStrictEqual(compose[0].dependencies.sort(),
                                       ranges.map((t) => t.name).sort()));
    check(() => assert.deepStrictEqual(compose[0].commands[0].parameters.args,
                                       ["-m", "omis", "compose", job, "--unit", `${k}`,
                                        "--tiles-per-part", `${perTask}`]));
});
// 80×48: 15 tiles in 4 tasks + compose; the corner unit: 1; 1024×512: 2048 tiles in 512 + 1.
check(() => assert.strictEqual(tasks.length, 5 + 1 + 513));

for (const [units, message] of [["not json", /not JSON/], ["[]", /non-empty/],
                                ['[{"kind": "uv", "width": 0, "height": 4}]', /width and height/],
                                ['[{"kind": "image"}]', /kind/]]) {
    const bad = JSON.parse(JSON.stringify(recorded));
    bad.settings.units = units;
    check(() => assert.throws(() => compile(script, bad), message));
}
console.log(`${checks} passed, 0 failed`);
