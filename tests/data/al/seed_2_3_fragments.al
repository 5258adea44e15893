{ The code fragments of Taylor's sections 2.2-2.3.7, each in a block named by its seed lines.
  Source: seeds/000_1457622cbb9a2614.txt L1169-1538 (fragments only; they are not meant to
  run together, and some use variables declared nowhere).
  Elisions dropped: the ":" lines (L1187, L1346, L1530) and "rigidly ... ;" (L1466) -> "rigidly;".
  OCR slips fixed (seed-al-subset.md section 6, al-language.md section 10):
    L1204  force(xhat)=0,4 (footnote mark 4)  -> force(xhat)=0,
    L1338  blue+trans(...)                    -> blue*trans(...)
    L1373, L1379, L1394, L1399  x + true/false (arrow misread as plus) -> arrow
    L1413  force(pin-zhat)                    -> force(pin*zhat)
    L1416  inv(in_hole_position)·pin·vector   -> inv(in_hole_position)*pin*vector
    L1446  inv(spot_on_surface)*pin+vector    -> inv(spot_on_surface)*pin*vector
    L1451  inv(in_hole_position)*pin+vector   -> inv(in_hole_position)*pin*vector
    L1467-1468  an unclosed brace before "move down until hit the spot" -> a closed comment
  Kept as printed although loosely typed (the interpreter decides): pin+rot(xhat,10*deg)
  (L1390), force(pin*zhat). }

begin "L1169 affix semantics"
  box_grasp ← box*grasp_xf;
  affix box_grasp to box at grasp_xf;
  affix cover to box;
  affix box to blue;
  move blue to box_grasp via grasp_approach;
  move box to new_box_place via midair_point;
end;

begin "L1202 carburetor"
  move carburetor to inspection_station
    via unloading_point
      where force(xhat)=0,
            force(yhat)=0,
            duration > 2*sec
      via approach_point
      on force(zhat) > 8*oz do
        stop
      on electric_eye_interrupt do
        signal passed_checkpoint;
end;

begin "pin-in-hole"
{ Declarations and initial affixments }
{ Grasp the pin }
{ Extract & transport over hole }
{ Insert }
{ Let go of the pin }
end;

begin "L1286 grasp"
  open bfingers to 1.0*inches;
  { The 1.0*INCHES is sort of arbitrary. }
  move blue to pin_grasp;
  close bfingers;
  affix pin to blue;
  { The pin will move if the hand does. }
  close blue
    with force(xhat)=0, force(yhat)=0;
end;

begin "L1338 withdraw"
  move blue to bpark via blue*trans(nilrot, vector(0,0,-3*cm));
  begin
    frame withdraw_3;
    affix withdraw_3 to blue at trans(nilrot, vector(0,0,-3*cm));
    move blue to bpark via withdraw_3;
  end;
end;

begin "L1373 missing the hole"
  in_hole_flag ← true; { Assume it will work }
  move pin to in_hole_position
    via pin_withdraw, hole_approach
    on force(pin*zhat) > 8*oz do
      begin
      stop; { Stop the motion }
      in_hole_flag ← false; { We lost }
      end
end;

begin "L1390 post-insertion check"
  move pin to pin+rot(xhat,10*deg)
    on torque(xhat) > 10*oz*inches do
      begin
      stop;
      in_hole_check ← true;
      end
    on arrival do
      begin
      { If the motion goes all the way, we lost }
      in_hole_check ← false;
      end;
end;

begin "L1411 always stop on force"
  move pin to in_hole_position+vector(0,0,-.3*inches)
  via pin_withdraw, hole_approach
  on force(pin*zhat)> 8*oz do
    stop;

  distance_off ← zhat · inv(in_hole_position)*pin*vector(0,0,0);

  if distance_off < -.2*inches then
    missed_box_flag ← true
  else if distance_off > .2*inches then
    hit_top_flag ← true
  else
    in_hole_flag ← true;
end;

begin "L1437 tapping"
  move pin to spot_on_surface+vector(0,0,-1.0*inches)
  via pin_withdraw,spot_on_surface+vector(0,0,1.0*inches)
  on force(pin*zhat) > 8*oz do stop
  on arrival do
  begin
  { This should never happen }
  abort("Help! Help! The box has been stolen");
  end;

  correction ← zhat · inv(spot_on_surface)*pin*vector(0,0,0);

  move pin to in_hole_position via hole_approach
  on force(pin*zhat) > 8*oz do stop;

  distance_off ← zhat · inv(in_hole_position)*pin*vector(0,0,0) - correction;
  { et cetera }
  box ← box + vector(0,0,correction);
end;

begin "L1466 rigid affixment"
  affix spot_on_surface to box rigidly;
  { move down until hit the spot }
  move pin to spot_on_surface+vector(0,0,-1.0*inches)
  on force(pin*zhat) > 8*oz do stop;

  { Say that's where we got to }
  spot_on_surface ← pin;
end;

begin "L1488 error recovery"
  if not in_hole_flag then
      abort("Pin is not in hole.");
  if not in_hole_flag then
      begin { Put your toys away }
          move pin to pin_holder via pin_withdraw;
          { We really should do some checking here, too }
          open bfingers to 1.0*inches;
          unfix blue from pin;
          move blue to bpark via pin_grasp_approach;
          abort("Pin is not in hole.");
      end;
end;

begin "L1516 search"
  if not in_hole_flag then
  begin
  vector dp;
  scalar n;
  dp ← vector(0.1*inches,0,0);
  for n ← 1 step 1 until 6 do
  begin
  dp ← rot(zhat,60*deg)*dp;
  { Try to put pin in perturbed hole }

  move pin to in_hole_position+dp+vector(0,0,-1.*inches)
  via hole_approach+dp+vector(0,0,1*inches)
  on force(pin*zhat) > 8*oz do stop;
  { Check distance travelled, etc. }
  if in_hole_flag then
  n←7; { This terminates the search }
  end;

  if not in_hole_flag then
  abort("The hole doesn't seem to be there");
  end;
end;
