// The operator page (cnc ui web): it shows the status the server pushes over the public API
// (JSON-RPC 2.0 on /api/v1/ws, link.js) and sends commands through it. Vanilla JavaScript
// modules, no framework, no build step; the API is in cnc/ui/web/API.md.
//
// machine.js comes first: it holds STOP, E-STOP and Esc, which act before anything else.

import { start } from "./machine.js";
import "./notices.js";
import "./program.js";
import { showView } from "./views.js";

showView("run");
start();
