{ Taylor's generated program for the pin-in-hole task of section 4.8 (strategy 130523, with a
  search loop and no tap); runs on fixture seed_4_8.
  Source: seeds/000_1457622cbb9a2614.txt L2715-2781 (L2744-2751, a footnote and page number
  between the two halves of the listing, dropped).
  The generator's own comments are kept in the tolerant bang form in which the listing prints
  them (the generator wrote braces, L2490). Assignments keep the generator's "=" form.
  OCR slips fixed (seed-al-subset.md section 6):
    L2739, L2743, L2776, L2780  comment delimiters I, IPINI    -> bang (IPINI = bang PIN1)
    L2735  8*DZ                         -> 8*OZ
    L2737  DISTANCE_OFF-ZHAT . ...      -> DISTANCE_OFF=ZHAT . ...
    L2755  W<259 degree-sign DEG        -> W<359*DEG   (a full circle; 359 so W=0 is not repeated)
    L2757  ABS(X+R*COS(W)), ABS(Y+R*SIN(W)) -> ABS(X<-R*COS(W)), ABS(Y<-R*SIN(W)) (arrow)
    L2759  BH1+TRANS(...)               -> BH1*TRANS(...)
    L2760  SETPNT; TRANS(... 90.0 degree-sign DEG ...) -> SETPNT*TRANS(... 90.0*DEG ...)
    L2761  SETPNT+TRANS(... degree-sign DEG ...) -> SETPNT*TRANS(... *DEG ...)
    L2762  8e02                         -> 8*OZ
    L2764  SETPNT+TRANS(... degree-sign DEG ...) -> SETPNT*TRANS(... *DEG ...)
    L2781  BMANIP+TRANS(...)            -> BMANIP*TRANS(...)   (the tap listing, L2844, has *) }

! PIN-IN-HOLE STRATEGY 130523:
DROK = .762      FPX = 1.58      FPY = 1.15      FPW = 1.05
DZ = .127      ESTIMATED TIME = 6.14 !

! PICKUP 72827:
W = 315. deg Grasp Angle = 180. deg Grasp Distance = 3.54 !

OPEN BHAND TO 2.98;
MOVE BMANIP TO PIN1*TRANS(ROTN(VECTOR(.924,.383,.001),180.*DEG),VECTOR(0,0,3.54))
  VIA PIN1*TRANS(ROTN(VECTOR(.924,.383,.001),180.*DEG),VECTOR(0,0,8.62));
CENTER BMANIP
  ON OPENING < .185 DO
    BEGIN ABORT("GRASP FAILED"); END;
AFFIX PIN1 TO BMANIP;
MOVE PIN1 TO PIN1*TRANS(NILROTN,VECTOR(0,0,6.79));

! FIRST ATTEMPT !

MOVE PIN1 TO BH1*TRANS(ROTN(ZHAT,90.0*DEG),VECTOR(0,0,-4.25))
  VIA BH1*TRANS(ROTN(ZHAT,90.0*DEG),VECTOR(0,0,2.54))
  ON FORCE(ORIENT(PIN1)*ZHAT) > 8*OZ DO STOP
  ON ARRIVAL DO ABORT("EXPECTED A FORCE HERE");
DISTANCE_OFF=ZHAT . INV(BH1*TRANS(ROTN(ZHAT,90.0*DEG),VECTOR(0,0,-1.71)))*DISPL(PIN1);
IF ABS(DISTANCE_OFF) > .169 THEN
  BEGIN ! PIN1 MISSED BH1 !
  BOOLEAN FLAG;
  ! SEARCH LOOP: !
  REAL R,DW,W,X,Y;FLAG=FALSE;
  R = .572; ! 0.75*DROK !
  WHILE NOT FLAG AND R ≤ 1.72 DO
    BEGIN
      W = 0; DW = (.572/R)*RAD;
      WHILE NOT FLAG AND W<359*DEG DO
        BEGIN
          IF ABS(X←R*COS(W))< 1.58 AND ABS(Y←R*SIN(W))< 1.15 THEN
            BEGIN FRAME SETPNT;
            SETPNT=BH1*TRANS(NILROTN,ROT(ZHAT,1.05)*VECTOR(X,Y,0));
            MOVE PIN1 TO SETPNT*TRANS(ROTN(ZHAT,90.0*DEG),VECTOR(0,0,-4.25))
              VIA SETPNT*TRANS(ROTN(ZHAT,90.0*DEG),VECTOR(0,0,2.54))
              ON FORCE(ORIENT(PIN1)*ZHAT) > 8*OZ DO STOP
              ON ARRIVAL DO ABORT("EXPECTED A FORCE HERE");
              DISTANCE_OFF=ZHAT . INV(SETPNT*TRANS(ROTN(ZHAT,90.0*DEG),VECTOR(0,0,-1.71)))
                *DISPL(PIN1);
            IF ABS(DISTANCE_OFF) < .169 THEN
              FLAG=TRUE;
            END;
          W=W+DW;
        END;
      R=R + .572;
    END;
  IF NOT FLAG THEN ABORT("PIN1 MISSED BH1");
END;

! LET GO !
OPEN BHAND TO 2.98;
UNFIX PIN1 FROM BMANIP;

! NOW GET HAND CLEAR !
MOVE BMANIP TO BMANIP*TRANS(NILROTN,VECTOR(0,0,-5.08));
