{ Taylor's generated program for the variation of section 4.8 (strategy 134356: box known in x,
  y and rotation but +-0.75 inch in z, so a tap and no search); runs on fixture seed_4_8_tap.
  Source: seeds/000_1457622cbb9a2614.txt L2804-2844.
  The generator's comments are written with braces, as its code writer printed them (L2490).
  Assignments keep the generator's "=" form.
  OCR slips fixed (seed-al-subset.md section 6):
    L2804-2809, L2821, L2829, L2839, L2843  comment delimiters I ... 1 -> braces
    L2818  RFFIX                        -> AFFIX
    L2825, L2833  8*DZ                  -> 8*OZ
  FPM = .524 in the header comment (read FPW) is comment text and left alone. }

{ PIN-IN-HOLE STRATEGY 134356:
DROK = .762      FPX = .243      FPY = .226      FPM = .524
DZ = .188      ESTIMATED TIME = 6.67      }

{ PICKUP 147157:
W = 98.0 deg  Grasp Angle = 135. deg  Grasp Distance = 3.54 }

OPEN BHAND TO 2.98;
MOVE BMANIP TO PIN1*TRANS(ROTN(VECTOR(.679,.679,.281),149*DEG),VECTOR(0,0,3.54))
  VIA PIN1*TRANS(ROTN(VECTOR(.679,.679,.281),149*DEG),VECTOR(-3.59,0,7.13));
CENTER BMANIP
  ON OPENING < .185 DO
    BEGIN ABORT("GRASP FAILED"); END;

AFFIX PIN1 TO BMANIP;
MOVE PIN1 TO PIN1*TRANS(NILROTN,VECTOR(0,0,6.79));

{ MUST TAP }

MOVE PIN1 TO BH1*TRANS(NILROTN,VECTOR(-1.21,-.002,-5.08))
  VIA BH1*TRANS(NILROTN,VECTOR(-1.21,-.002,5.08))
    ON FORCE(ORIENT(PIN1)*ZHAT) > 8*OZ DO STOP
    ON ARRIVAL DO ABORT("EXPECTED A FORCE HERE");
CORR = ZHAT . INV(BH1*TRANS(NILROTN,VECTOR(-1.21,-.002, .000)))*DISPL(PIN1);

{ FIRST ATTEMPT }

MOVE PIN1 TO BH1*TRANS(ROTN(ZHAT,90.0*DEG),VECTOR(0,0,-4.25))
  VIA BH1*TRANS(ROTN(ZHAT,90.0*DEG),VECTOR(0,0,2.54))
    ON FORCE(ORIENT(PIN1)*ZHAT) > 8*OZ DO STOP
    ON ARRIVAL DO ABORT("EXPECTED A FORCE HERE");
DISTANCE_OFF=ZHAT.INV(BH1*TRANS(ROTN(ZHAT,90.0*DEG),VECTOR(0,0,-1.71)))*DISPL(PIN1)-CORR;
IF ABS(DISTANCE_OFF) > .239 THEN
  ABORT("PIN1 MISSED BH1 UNEXPECTEDLY.");

{ LET GO }
OPEN BHAND TO 2.98;
UNFIX PIN1 FROM BMANIP;

{ NOW GET HAND CLEAR }
MOVE BMANIP TO BMANIP*TRANS(NILROTN,VECTOR(0,0,-5.08));
