; upload.cmd - send a saved program file back to uTile (manual 6.1.3)
;
; Usage at the C-Kermit> prompt:  upload [file]        (default utile.hex)
; uTile must be at its editor screen. Only a wholly valid file replaces uTile's UF0 and
; timer presets; STORE keeps it in EEPROM.

local file
assign file \%1
if not def file assign file utile.hex
if not exist \m(file) end 1 {File not found!}

output READ\13
input 5 {'/' to abort}
if fail end 1 {uTile did not answer READ - is it at the editor screen?}
input 1 {\255}
clear input

; Plain text, each line ended by CR, without waiting for echoes or prompts.
set transmit echo off
set transmit prompt 0
set transmit linefeed off
set transmit pause 0
transmit /text \m(file)
if fail {
    output /
    end 1 {Could not send \m(file)}
}
input 10 {'CR' for menu -->}
if fail end 1 {uTile did not confirm the transfer}
local result
assign result \v(input)
output \13
if not match {\m(result)} {*File read completed*} end 1 {uTile refused \m(file) (see its message above)}
echo
echo Sent \m(file) to uTile
