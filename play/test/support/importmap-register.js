// `node --import` this: avr8js resolved through play/importmap.js's import map, as a page
// resolves it (importmap-hooks.js).

import { register } from 'node:module';
import { pathToFileURL } from 'node:url';
import { ESM_DIR, avr8jsImportMap } from '../../importmap.js';

const { imports } = avr8jsImportMap(`${pathToFileURL(ESM_DIR).href}/`);
register('./importmap-hooks.js', import.meta.url, { data: { imports } });
