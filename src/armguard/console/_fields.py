"""Typed-value fields committed on Enter or on leaving the field, never keystroke by keystroke.

viser's number boxes send every keystroke, so typing ``-300`` applied ``-3`` and ``-30`` on the
way, and a refused value had already changed the state.  A :class:`TypedField` is a text box in
its own form; :data:`COMMIT_ON_BLUR_HTML` (added once to the page) keeps its keystrokes in the
browser's box (the page's handlers, and so the server, never see an intermediate state), and on
Enter or on leaving the field hands the box's whole text to the page once and submits the form;
the server acts only on that submit, reading the box's value in message order and running the
commits one at a time in the order they were typed.  While a box has focus and holds typed text, a value pushed
by the server does not overwrite it.  On a refusal the box is put back to the value in force.

Why not per keystroke: the page sends GUI messages through one 50 ms throttle that keeps only
the latest message, so the form's "dirty" notice sent after a fast keystroke replaced that
keystroke's value update (``70`` typed without delay arrived as ``7``).

The same snippet hides the number boxes beside viser's sliders (sliders are for dragging,
typed values go through the fields) and keeps the status panel in sight: its block is sticky at
the top of the scrolling control panel, the controls scroll beneath it; the panel never scrolls
sideways (long names wrap, see :mod:`._readout`).
"""

from __future__ import annotations

import traceback
from concurrent.futures import ThreadPoolExecutor

__all__ = ["TypedField", "COMMIT_ON_BLUR_HTML", "COMMIT_GAP_MS"]

_COMMITS = ThreadPoolExecutor(max_workers=1, thread_name_prefix="armguard-commit")
"""Runs every field's commit, one at a time in the order they were typed: a slow one (a check that
compiles its kernels) never lets a later one run first and overwrite its result or message."""


def _report(done) -> None:
    exc = done.exception()
    if exc is not None:
        traceback.print_exception(exc)

COMMIT_GAP_MS = 60
"""Milliseconds with no GUI message sent that the page waits for before it sends one of its own:
a commit's value update, its submit, and every click on a button.

The page sends every GUI message through one 50 ms throttle that keeps only the latest message:
a message handed to it within 50 ms of the one before waits, and the next message replaces it.
A commit's value update is followed at once by the form's "dirty" notice, so a value typed within
50 ms of another GUI message (a dropdown's choice, a keystroke in a plain text box) never reached
the server, and its submit then applied the old value (seen now and then in the browser tests
on a loaded 2-core machine, ``test_jog_plus_x_in_tool_coordinates_moves_along_the_tool_x``: the
submit arrived with the old value and no value update before it; with a click into the next
field 60-300 ms after an Enter, 7 of 26 typed values were once lost).  The page therefore watches
the GUI messages that go out (``Worker.prototype.postMessage``, viser's websocket worker): each of
its own waits, on a timer (due after the throttle's own), until none has gone out for this long,
so that the throttle is idle and sends it at once.  Under load the throttle's own timer can run
after the page's, later than it was due (seen with two browser tests at once on 2 cores), and the
throttle then still holds the message: the page sees that nothing went out, waits,
and acts again if the held message was replaced rather than sent (a value, at most 5 times; a
submit or a click only when it never went out, so that nothing acts twice).  Commits and clicks go
out one at a time from a queue: a click on a button while a commit is under way waits for its
submit, so the server sees the typed value before the button acts on it."""

_JS = (
    "if(!window.__armguardBlur){window.__armguardBlur=1;var pass=false;var QUIET=" + str(COMMIT_GAP_MS) + ";"
    "var isField=function(t){return !!(t&&t.tagName==='INPUT'&&t.dataset&&t.dataset.armguardField);};"
    "var field=function(t){return isField(t)&&t.closest?t.closest('form'):null;};"
    # keystrokes stay in the box: the page's own handlers (and so the server) never see them
    # (the change event a blur fires after a commit is no new typing: it commits nothing again)
    "var hold=function(e){if(!pass&&isField(e.target)){if(e.type==='input')e.target.__agTyped=true;e.stopImmediatePropagation();}};"
    "document.addEventListener('input',hold,true);document.addEventListener('change',hold,true);"
    # the GUI messages that went out (viser's websocket worker carries them): when the last did, how many of each
    "var last=-1e9,sent={},post=Worker.prototype.postMessage;"
    "Worker.prototype.postMessage=function(d){var m=d&&d.type==='send'?d.message:null;"
    "if(m&&typeof m.type==='string'&&m.type.indexOf('Gui')===0){last=performance.now();"
    "sent[m.type]=(sent[m.type]||0)+1;if(m.uuid){var k=m.type+':'+m.uuid;sent[k]=(sent[k]||0)+1;}}"
    "return post.apply(this,arguments);};"
    "var count=function(k){return sent[k]||0;};"
    # fn once no GUI message has gone out for QUIET ms
    "var quiet=function(fn){setTimeout(function(){if(performance.now()-last<QUIET)quiet(fn);else fn();},"
    "Math.max(1,QUIET-(performance.now()-last)));};"
    # act into an idle throttle; a message it held instead of sending (a timer ran late) is awaited,
    # and the act repeated (at most 5 times) only if the message never went out (it was replaced)
    "var emit=function(act,key,done,tries){quiet(function(){var c0=count(key);act();if(count(key)>c0||tries>=5){done();return;}"
    "quiet(function(){if(count(key)>c0)done();else emit(act,key,done,tries+1);});});};"
    # on Enter / blur: queue the box's whole text; commits and clicks go out one at a time (see COMMIT_GAP_MS)
    "var proto=Object.getOwnPropertyDescriptor(HTMLInputElement.prototype,'value');"
    "var queue=[],busy=false;"
    "var run=function(){if(busy||!queue.length)return;busy=true;var c=queue.shift();"
    "var next=function(){busy=false;run();};"
    "if(c.b){emit(function(){pass=true;try{c.b.click();}finally{pass=false;}},'GuiUpdateMessage:'+c.b.id,next,1);return;}"
    # the value set through the page's own setter first (another text), so that the input event is a change to it
    "emit(function(){c.t.value=c.text+' ';proto.set.call(c.t,c.text);pass=true;"
    "try{c.t.dispatchEvent(new Event('input',{bubbles:true}));}finally{pass=false;}},'GuiUpdateMessage',"
    "function(){emit(function(){if(c.f.requestSubmit)c.f.requestSubmit();},'GuiFormSubmitMessage',next,1);},1);};"
    "var commit=function(t){var f=field(t);if(!f)return;t.__agTyped=false;"
    "queue.push({t:t,f:f,text:t.value});run();};"
    "document.addEventListener('keydown',function(e){if(e.key!=='Enter'||!isField(e.target))return;"
    "e.preventDefault();e.stopPropagation();commit(e.target);},true);"
    # leaving a box commits only what was typed since its last commit (Enter then a click: once)
    "document.addEventListener('focusout',function(e){if(isField(e.target)&&e.target.__agTyped)commit(e.target);},true);"
    # a click on a GUI button (its id the element's uuid; other buttons act in the page only) goes out
    # from the queue too: after the commits before it, into an idle throttle
    "document.addEventListener('click',function(e){if(pass)return;"
    "var b=e.target&&e.target.closest?e.target.closest('button[id]'):null;"
    "if(!b||b.type==='submit'||!/^[0-9a-f]{8}-[0-9a-f]{4}-/.test(b.id))return;"
    "e.preventDefault();e.stopImmediatePropagation();queue.push({b:b});run();},true);"
    # a value pushed by the server never overwrites what is being typed in the focused box
    "var guard=function(i){var d=Object.getOwnPropertyDescriptor(i,'value')||proto;"
    "Object.defineProperty(i,'value',{configurable:true,get:function(){return d.get.call(i);},"
    "set:function(v){if(i.__agTyped&&document.activeElement===i)return;d.set.call(i,v);}});};"
    "var mark=function(){document.querySelectorAll('form input:not([type]),form input[type=text]').forEach(function(i){"
    "if(!i.dataset.armguardField){i.dataset.armguardField='1';guard(i);}});};"
    "new MutationObserver(mark).observe(document.body,{childList:true,subtree:true});mark();}"
)

STALE_AFTER_MS = 1000
"""Milliseconds without a connection after which the status panel is covered by "NO CONNECTION"."""

_STALE_JS = (
    # viser keeps its last GUI on screen, dimmed, when the server goes: the status panel's last CLEAR
    # stayed readable.  With no connection (viser's connected icon gone) for STALE_AFTER_MS, the panel
    # is covered by a red notice that there is no verdict; a reconnection's fresh panel takes it away.
    "if(!window.__armguardStale){window.__armguardStale=1;var seen=false,gone=0;"
    "setInterval(function(){var up=!!document.querySelector('.tabler-icon-cloud-check');"
    "var p=document.getElementById('armguard-status');var o=document.getElementById('armguard-stale');"
    "if(up){seen=true;gone=0;if(o)o.remove();return;}"
    "if(!seen||!p)return;gone+=250;if(gone<" + str(STALE_AFTER_MS) + "||o)return;"
    "o=document.createElement('div');o.id='armguard-stale';"
    "o.textContent='NO CONNECTION: no verdict (the status under this is from before the connection was lost)';"
    "o.style.cssText='position:absolute;inset:0;z-index:5;display:flex;align-items:center;justify-content:center;"
    "text-align:center;background:rgba(170,0,0,0.94);color:#fff;font-weight:700;font-size:1.1em;padding:8px';"
    "p.style.position='relative';p.appendChild(o);},250);}"
)

COMMIT_ON_BLUR_HTML = (
    "<style>.mantine-Slider-root + .mantine-NumberInput-root{display:none !important}"
    # the status panel stays in sight: the controls scroll beneath it
    # (sticky needs every box between it and the scrolling one to let it overflow)
    ".mantine-ScrollArea-content div:has(#armguard-status){overflow:visible !important}"
    "div:has(> #armguard-status){position:sticky;top:0;z-index:3;background:#fff;padding-bottom:2px;max-width:100%}"
    # the control panel never scrolls sideways (scrolled, it cut the panel's left edge): what is
    # wider than it wraps (the panel's names) or is held to its width (labels, boxes)
    ".mantine-ScrollArea-viewport:has(#armguard-status){overflow-x:hidden !important}"
    ".mantine-ScrollArea-content:has(#armguard-status){min-width:0 !important;max-width:100%}</style>"
    f'<img src="data:," alt="" style="display:none" onerror="{_JS}{_STALE_JS}">'
)
"""HTML for ``gui.add_html``: submits a typed field's form on blur; hides sliders' number boxes;
keeps the status panel on top while the controls scroll; covers it with "NO CONNECTION" when the
server is gone (:data:`STALE_AFTER_MS`)."""


class TypedField:
    """A text field for one value: ``on_commit(text)`` runs on Enter or blur, with the typed text.

    ``shown`` is the text the box shows for the value in force; :meth:`show` updates it (only
    when it changed, so a refresh never overwrites what is being typed) and :meth:`revert` puts
    the box back to it after a refusal.  ``on_same()`` runs instead of ``on_commit`` when the text
    typed is the value in force (nothing to apply: the refusal of a value typed before it goes).
    """

    def __init__(self, gui, label: str, text: str, on_commit, *, hint: str | None = None, on_same=None) -> None:
        self.label = label
        self.shown = text
        with gui.add_form(None) as form:
            self.handle = gui.add_text(label, text, hint=hint)
        self.form = form

        def apply(typed: str) -> None:
            if typed.strip() == self.shown.strip():  # the value in force, typed again: nothing new
                if on_same is not None:
                    on_same()
                return
            on_commit(typed)

        async def submit(event) -> None:
            # on the event loop, in message order: the value update the page sent before this
            # submit has landed, and no later one has (see COMMIT_GAP_MS)
            if event.client is None:
                return
            _COMMITS.submit(apply, str(self.handle.value)).add_done_callback(_report)

        form.on_submit(submit)
        self.enter = apply
        """``enter(typed)``: what Enter (or leaving the box) does with ``typed``, run here at once
        (the browser's submit queues it on the commit thread); tests call it without a browser."""

    @property
    def visible(self) -> bool:
        """Whether the field (its form, with the box) is shown."""
        return bool(self.form.visible)

    @visible.setter
    def visible(self, on: bool) -> None:
        if bool(self.form.visible) != bool(on):
            self.form.visible = bool(on)

    def show(self, text: str) -> None:
        if text != self.shown:
            self.shown = text
            self.handle.value = text

    def revert(self) -> None:
        self.handle.value = self.shown
