// Validates ops/k8s/*.yaml offline (issue 16): every object against the
// Kubernetes API schemas (kubernetes-models, from the OpenAPI definitions),
// then what fabatlas' deployment relies on: probes that work under TLS
// (HTTP on the plaintext metrics port, or TCP), non-root read-only
// containers without privilege escalation, requests and limits, workers
// that mount the CA, client certificate and token but never the server key,
// a headless Service for the StatefulSet. A deliberately broken copy must be
// rejected, so a validator that accepts anything fails this test.
//   node tests/ops/k8s_validate.mjs ops/k8s
import fs from "node:fs";
import path from "node:path";
import YAML from "yaml";

const dir = process.argv[2];
const problems = [];
const fail = (where, what) => problems.push(`${where}: ${what}`);

async function modelOf(doc) {
  const [group, version] = doc.apiVersion.includes("/") ? doc.apiVersion.split("/") : ["", doc.apiVersion];
  const module = group ? `kubernetes-models/${group}/${version}/${doc.kind}` : `kubernetes-models/${version}/${doc.kind}`;
  return (await import(module))[doc.kind];
}

async function schemaErrors(doc) {
  try {
    new (await modelOf(doc))(doc).validate();
    return null;
  } catch (e) {
    return String(e.message || e).split("\n")[0];
  }
}

const objects = [];
for (const file of fs.readdirSync(dir).filter((f) => f.endsWith(".yaml")).sort()) {
  const text = fs.readFileSync(path.join(dir, file), "utf8");
  for (const d of YAML.parseAllDocuments(text)) {
    if (d.errors.length) fail(file, `YAML: ${d.errors[0].message}`);
    const doc = d.toJSON();
    if (!doc) continue;
    const where = `${file}: ${doc.kind}/${doc.metadata?.name}`;
    const err = await schemaErrors(doc);
    if (err) fail(where, `schema: ${err}`);
    objects.push({ where, doc });
  }
}

// The validator itself rejects what the API server would.
const broken = structuredClone(objects.find((o) => o.doc.kind === "Deployment").doc);
broken.spec.template.spec.containers[0].ports[0].containerPort = "nine";
if (!(await schemaErrors(broken))) fail("validator", "accepted a containerPort that is not an integer");
const unknownKind = { apiVersion: "apps/v1", kind: "Deployment", metadata: { name: "x" }, spec: {} };
if (!(await schemaErrors(unknownKind))) fail("validator", "accepted a Deployment without selector and template");

const workloads = objects.filter((o) => ["StatefulSet", "Deployment"].includes(o.doc.kind));
if (workloads.length !== 2) fail("manifests", `expected a StatefulSet and a Deployment, found ${workloads.length} workloads`);
for (const { where, doc } of workloads) {
  const pod = doc.spec.template.spec;
  if (pod.securityContext?.runAsNonRoot !== true) fail(where, "pod securityContext.runAsNonRoot is not true");
  for (const c of pod.containers) {
    const at = `${where} container ${c.name}`;
    const sc = c.securityContext || {};
    if (sc.readOnlyRootFilesystem !== true) fail(at, "root file system is not read-only");
    if (sc.allowPrivilegeEscalation !== false) fail(at, "allowPrivilegeEscalation is not false");
    if (!(sc.capabilities?.drop || []).includes("ALL")) fail(at, "capabilities are not all dropped");
    for (const kind of ["requests", "limits"])
      for (const r of ["cpu", "memory"]) if (!c.resources?.[kind]?.[r]) fail(at, `no resources.${kind}.${r}`);
    const ports = new Map((c.ports || []).map((p) => [p.name, p.containerPort]));
    const args = c.command || [];
    const metricsArg = args[args.indexOf("--metrics") + 1] || "";
    for (const probe of ["readinessProbe", "livenessProbe"]) {
      const p = c[probe];
      if (!p) { fail(at, `no ${probe}`); continue; }
      if (p.grpc) fail(at, `${probe} is a gRPC probe, which cannot speak TLS`);
      if (p.httpGet) {
        const port = typeof p.httpGet.port === "string" ? ports.get(p.httpGet.port) : p.httpGet.port;
        if (!metricsArg.endsWith(`:${port}`)) fail(at, `${probe} HTTP port ${p.httpGet.port} is not the plaintext --metrics port`);
        if (p.httpGet.path !== "/healthz") fail(at, `${probe} path ${p.httpGet.path} is not /healthz`);
      }
      if (!p.httpGet && !p.tcpSocket && !p.exec) fail(at, `${probe} has no handler`);
    }
    if (!args.includes("--tls-ca") && !args.includes("--tls-cert")) fail(at, "gRPC without TLS");
    if (!args.includes("--token-file")) fail(at, "no bearer token");
  }
}

const worker = workloads.find((o) => o.doc.kind === "Deployment");
if (worker) {
  const pod = worker.doc.spec.template.spec;
  const secrets = pod.volumes.filter((v) => v.secret).map((v) => v.secret.secretName);
  const server = objects.find((o) => o.doc.kind === "StatefulSet");
  const serverSecrets = server ? server.doc.spec.template.spec.volumes.filter((v) => v.secret).map((v) => v.secret.secretName) : [];
  const keySecret = serverSecrets.find((s) => s.includes("coordinator-tls"));
  if (!keySecret) fail("coordinator", "no secret holding the server key");
  if (secrets.includes(keySecret)) fail(worker.where, `mounts ${keySecret}, which holds the server key`);
  for (const need of ["fabatlas-ca", "fabatlas-token", "fabatlas-worker-tls"])
    if (!secrets.includes(need)) fail(worker.where, `does not mount ${need}`);
}

const sts = objects.find((o) => o.doc.kind === "StatefulSet");
if (sts) {
  const svc = objects.find((o) => o.doc.kind === "Service" && o.doc.metadata.name === sts.doc.spec.serviceName);
  if (!svc) fail(sts.where, `serviceName ${sts.doc.spec.serviceName} has no Service`);
  else if (svc.doc.spec.clusterIP !== "None") fail(svc.where, "the StatefulSet's Service is not headless (clusterIP: None)");
  if (!sts.doc.spec.volumeClaimTemplates?.length) fail(sts.where, "no persistent volume for the state directory");
}

if (problems.length) {
  for (const p of problems) console.log(p);
  console.log(`0 passed, ${problems.length} failed`);
  process.exit(1);
}
console.log(`${objects.length} Kubernetes objects valid against the API schemas and fabatlas' deployment rules`);
