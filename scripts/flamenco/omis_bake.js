// omis bake jobs on a Flamenco 3 farm: a job-type script for Flamenco Manager
// (copy it into the Manager's `scripts/` folder). A job is a bake job written
// by the omis_bake add-on's "Export Bake Job" (a scene snapshot and a job
// JSON on storage every worker reads); this script splits it by unit (one
// object into one image or colour attribute) and lightmaps further by tile
// range, and runs the omis command line on the workers:
//
//   python3 -m omis bake JOB --unit K --tiles FIRST:COUNT   one task a range
//   python3 -m omis compose JOB --unit K --tiles-per-part N after its ranges
//   python3 -m omis bake JOB --unit K                       a colour attribute
//
// Each range's texels get the bits a whole bake gives them (seeds are fixed
// by texel), so a re-queued task or a different worker changes nothing.
// Flamenco's compiler (goja) has no file access: the job's units come in the
// `units` setting (the JSON list "Export Bake Job" prints and stores beside
// the job, `units.json`).

const TILE = 16; // texels on a tile's side (omis.bake_tile_count)

const JOB_TYPE = {
    label: "omis Bake",
    description: "Bake direct lighting with omis, split by object and lightmap tile range",
    settings: [
        { key: "job_file", type: "string", subtype: "file_path", required: true,
          description: "The bake job (JSON) written by omis Bake's Export Bake Job" },
        { key: "units", type: "string", required: true, visible: "submission",
          description: "The job's units as JSON: [{kind, width, height, object}, ...] (units.json)" },
        { key: "tiles_per_task", type: "int32", default: 64, propargs: { min: 1, max: 65536 },
          description: "Lightmap tiles (16×16 texels) baked by one task" },
        { key: "python", type: "string", default: "python3", visible: "submission",
          description: "The Python that imports omis on the workers" },
    ],
};

function compileJob(job) {
    const settings = job.settings;
    const units = parseUnits(settings.units);
    const perTask = settings.tiles_per_task || 64;
    if (!(perTask >= 1)) throw "tiles_per_task must be at least 1";
    for (let k = 0; k < units.length; k++) {
        for (const task of unitTasks(settings, units[k], k, perTask)) job.addTask(task);
    }
}

function parseUnits(text) {
    let units;
    try {
        units = JSON.parse(text);
    } catch (e) {
        throw `units: not JSON (${e})`;
    }
    if (!Array.isArray(units) || units.length == 0) throw "units: expected a non-empty list";
    units.forEach((u, k) => {
        if (u.kind == "uv") {
            if (!(u.width >= 1 && u.height >= 1)) throw `units[${k}]: a lightmap needs width and height`;
        } else if (u.kind != "corner") {
            throw `units[${k}]: kind must be "uv" or "corner"`;
        }
    });
    return units;
}

// [first, count] ranges of perTask tiles in order, the last shorter (as
// `python3 -m omis compose --tiles-per-part` expects them).
function tileRanges(width, height, perTask) {
    const tiles = Math.ceil(width / TILE) * Math.ceil(height / TILE);
    const ranges = [];
    for (let first = 0; first < tiles; first += perTask)
        ranges.push([first, Math.min(perTask, tiles - first)]);
    return ranges;
}

function omisCommand(settings, args) {
    return author.Command("exec", { exe: settings.python, args: ["-m", "omis"].concat(args) });
}

function unitTasks(settings, unit, k, perTask) {
    const name = unit.object ? `${k}-${unit.object}` : `${k}`;
    if (unit.kind == "corner") {
        const task = author.Task(`bake-${name}`, "misc");
        task.addCommand(omisCommand(settings, ["bake", settings.job_file, "--unit", `${k}`]));
        return [task];
    }
    const tasks = [];
    const compose = author.Task(`compose-${name}`, "misc");
    compose.addCommand(omisCommand(settings, ["compose", settings.job_file, "--unit", `${k}`,
                                              "--tiles-per-part", `${perTask}`]));
    for (const [first, count] of tileRanges(unit.width, unit.height, perTask)) {
        const task = author.Task(`bake-${name}-tiles-${first}+${count}`, "misc");
        task.addCommand(omisCommand(settings, ["bake", settings.job_file, "--unit", `${k}`,
                                               "--tiles", `${first}:${count}`]));
        compose.addDependency(task);
        tasks.push(task);
    }
    tasks.push(compose);
    return tasks;
}
