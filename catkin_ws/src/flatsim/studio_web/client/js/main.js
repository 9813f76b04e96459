// The page: the connection, the 3D view and the panels, each panel one module
// (the Insert tab, the File menu and the editors too; see studio.js).

import {Connection} from './connection.js';
import {SceneView} from './scene/view.js';
import {Studio} from './studio.js';
import * as alerts from './panels/alerts.js';
import * as editTools from './panels/edit_tools.js';
import * as menus from './panels/menus.js';
import * as modelMenu from './panels/model_menu.js';
import * as undo from './panels/undo.js';
import * as toolbar from './panels/toolbar.js';
import * as worldTab from './panels/world_tab.js';
import * as skippedList from './panels/skipped_list.js';
import * as timePanel from './panels/time_panel.js';
import * as cameraPanel from './panels/camera_panel.js';
import * as chasePanel from './panels/chase_panel.js';
import * as views from './panels/views.js';
import * as insertTab from './panels/insert_tab.js';
import * as fileMenu from './panels/file_menu.js';
import * as buildingEditor from './panels/building_editor.js';
import * as modelEditor from './panels/model_editor.js';

// The order is the order of their parts on the page (the World tab before Insert, the toolbar's
// tools before the shapes); a panel needs only the studio's hooks, there before any mounts.
const PANELS = [alerts, editTools, menus, undo, modelMenu, toolbar, worldTab, insertTab, skippedList, timePanel,
                cameraPanel, chasePanel, views, fileMenu, buildingEditor, modelEditor];

const token = new URLSearchParams(window.location.search).get('token') || '';
const connection = new Connection(token);
const view = new SceneView(document.getElementById('view'));
const studio = new Studio(connection, view);
for (const panel of PANELS) panel.mount(studio);
// For tests and the benchmark: the running studio, as the page's code sees it.
window.studio = studio;
connection.open();
