; download.cmd - save uTile's UF0 program and timer presets to a file (manual 6.1.2)
;
; Usage at the C-Kermit> prompt:  download [file]      (default utile.hex)
; uTile must be at its editor screen. The file is the Intel HEX that WRITE sends.

local file
assign file \%1
if not def file assign file utile.hex

; Ask uTile to send and wait for its prompt.
output WRITE\13
input 5 {'/' to abort}
if fail end 1 {uTile did not answer WRITE - is it at the editor screen?}
; Let the rest of the screen arrive, then forget it: the file gets only the records.
input 1 {\255}
clear input

set session-log text
log session \m(file)
if fail {
    output /
    end 1 {Cannot write \m(file)}
}
output \13
input 10 {:00000001FF}
if fail {
    close session
    output \13
    end 1 {No end-of-file record from uTile - \m(file) is incomplete}
}
input 2 \10
close session
output \13
echo
echo Saved uTile program to \m(file)
