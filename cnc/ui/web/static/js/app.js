// The operator page (cnc ui web): it shows the status the server pushes over /ws and sends
// commands. Vanilla JavaScript modules, no framework, no build step; the protocol is in
// cnc/ui/web/server.py.
//
// machine.js comes first: it holds STOP, E-STOP and Esc, which act before anything else.

import { start } from "./machine.js";
import "./notices.js";
import "./program.js";
import { showView } from "./views.js";

showView("run");
start();
