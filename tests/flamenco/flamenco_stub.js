// A small stand-in for Flamenco Manager's job-compiler environment (goja):
// the `author` API (Task, Command), `print`, and `job.addTask`, enough to run
// a job-type script's compileJob under node and look at the tasks it authors.
// Run as `node flamenco_stub.js SCRIPT JOB.json`, it prints the tasks as JSON.
"use strict";
const fs = require("fs");
const vm = require("vm");

function makeAuthor() {
    return {
        Task(name, type) {
            const task = { name, type, commands: [], dependencies: [] };
            task.addCommand = (command) => task.commands.push(command);
            task.addDependency = (other) => task.dependencies.push(other.name);
            return task;
        },
        Command(type, parameters) {
            return { type, parameters };
        },
    };
}

// The tasks compileJob(job) adds, in order, as plain objects.
function compile(scriptPath, job) {
    const context = vm.createContext({ author: makeAuthor(), print: () => {}, JSON, Math });
    vm.runInContext(fs.readFileSync(scriptPath, "utf8") + "\nthis.JOB_TYPE = JOB_TYPE;", context,
                    { filename: scriptPath });
    const tasks = [];
    const submitted = Object.assign({}, job, { addTask: (task) => tasks.push(task) });
    context.compileJob(submitted);
    // Through JSON: plain values of this realm (the script's arrays are the context's).
    return JSON.parse(JSON.stringify({
        jobType: context.JOB_TYPE,
        tasks: tasks.map((t) => ({ name: t.name, type: t.type, commands: t.commands,
                                   dependencies: t.dependencies })),
    }));
}

module.exports = { compile };

if (require.main === module) {
    const [script, jobFile] = process.argv.slice(2);
    const result = compile(script, JSON.parse(fs.readFileSync(jobFile, "utf8")));
    process.stdout.write(JSON.stringify(result.tasks, null, 1) + "\n");
}
