// Node module hooks that resolve as a browser does with play/importmap.js's import map:
// the bare `avr8js` and avr8js's extensionless module URLs through the map, every module
// of its ES build as an ES module; a module of its CommonJS build is refused, so a run that
// works has used the ES build alone, as a page would. (Registered by importmap-register.js.)

let imports = {};

/** Takes the map from the registering module. */
export function initialize(data) {
  imports = data.imports;
}

export async function resolve(specifier, context, next) {
  const url = imports[specifier] ?? (/^\.{1,2}\//.test(specifier) && context.parentURL
    ? imports[new URL(specifier, context.parentURL).href]
    : undefined);
  if (url) return { url, format: 'module', shortCircuit: true };
  return next(specifier, context);
}

export async function load(url, context, next) {
  if (url.includes('/avr8js/dist/cjs/')) {
    throw new Error(`${url}: the CommonJS build was reached, not the ES build through the map`);
  }
  if (url.includes('/avr8js/dist/esm/')) return next(url, { ...context, format: 'module' });
  return next(url, context);
}
