{ Taylor's refined hand-written pin-in-hole program, section 2.3.8.
  Source: seeds/000_1457622cbb9a2614.txt L1549-1627 (L1562-1566 are page furniture, dropped).
  OCR slips fixed (seed-al-subset.md section 6, al-language.md section 10):
    L1598  vector(0,1*inches,0,0)        -> vector(0.1*inches,0,0)
    L1605  in_hole_position-dp           -> in_hole_position+dp   (as at L1526)
    L1612  in_hole_flag=true             -> in_hole_flag <- true  (arrow, as in hand-written code)
  Everything else, including lower case, nilrotN, the dot product written with a middle dot,
  and the empty statements before END, is as printed. }

begin "pin-in-hole"

frame pin, pin_grasp, pin_grasp_approach;
frame pin_holder, pin_withdraw;
frame hole, in_hole_position, hole_approach;
frame box;

affix pin_withdraw to pin_holder
at trans(rot(zhat,30*deg),vector(0,0,4*cm));
pin_holder ← frame(nilrotn,vector(15*inches,10*inches,0));

affix pin_grasp to pin at trans(rot(xhat,180*deg),vector(0,0,2*cm));
affix pin_grasp_approach to pin_grasp at trans(nilrotn,vector(0,0,-3*cm));
pin ← pin_holder;

affix in_hole_position to hole rigidly
  at trans(nilrotN, vector(0,0,-1*cm));
affix hole_approach to hole at trans(nilrotN, vector(0,0,+1*cm));
affix hole to box at trans(nilrotN, vector(5*cm,4*cm,3*cm));
box ← initial_box_position;

{ Grasp the pin }
open bfingers to 1.0*inches;
move blue to pin_grasp via pin_grasp_approach;
center bfingers
  on opening < 0.1*inches do
    begin
    stop;
    abort("Grasp failed to pick up pin");
    end;
affix pin to blue;

{ Extract, transport, and insert }
move pin to in_hole_position+vector(0,0,-3*inches)
  via pin_withdraw,hole_approach
  on force(pin*zhat) > 8*oz do
    stop;

distance_off ← zhat · inv(in_hole_position)*pin*vector(0,0,0);

if not ( 0.2*inches > distance_off > -0.2*inches ) then
  begin
  vector dp;
  scalar n; boolean in_hole_flag;
  dp ← vector(0.1*inches,0,0);
  in_hole_flag ← false; n←0;
  while (n←n+1) ≤ 6 and not in_hole_flag do
    begin
    dp ← rot(zhat,60*deg)*dp;

    { Try to put pin in perturbed hole }
    move pin to in_hole_position+dp+vector(0,0,-1.*inches)
      via hole_approach+dp+vector(0,0,1*inches)
      on force(pin*zhat) > 8*oz do stop;

    { Check distance travelled, etc. }
    distance_off ← zhat · inv(in_hole_position)*pin*vector(0,0,0);
    if 0.2*inches > distance_off > -0.2*inches then
      in_hole_flag ← true;
    end;

    if not in_hole_flag then
      abort("The hole doesn't seem to be there");
    end;

{ Let go of the pin }
open bfingers to 1.0*inches;
unfix pin from blue;
in_hole_position←pin; { Update our model }
move blue to bpark via pin_grasp_approach;
end;
